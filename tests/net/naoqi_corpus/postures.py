"""ALRobotPosture: every posture, families, applyPosture, errors."""

from _corpus import expect_error, session

s = session()
motion = s.service("ALMotion")
posture = s.service("ALRobotPosture")
motion.wakeUp()
names = posture.getPostureList()
assert {"Stand", "StandInit", "StandZero", "Crouch", "Sit", "SitRelax"} <= set(names), names
for name, family in [("Stand", "Standing"), ("Crouch", "Crouching"), ("StandInit", "Standing")]:
    assert posture.goToPosture(name, 0.8) is True, name
    assert posture.getPosture() == name, (name, posture.getPosture())
    assert posture.getPostureFamily() == family, (name, posture.getPostureFamily())
assert posture.applyPosture("StandZero", 1.0) is True
assert posture.getPostureFamily() == "Standing"
assert posture.goToPosture("StandInit", 1.0) is True
assert "Sitting" in posture.getPostureFamilyList()
expect_error(
    lambda: posture.goToPosture("Handstand", 0.5), "ALRobotPosture.goToPosture", "Handstand"
)
expect_error(lambda: posture.goToPosture("Stand", 1.5), "(0, 1]")
motion.rest()
assert motion.robotIsWakeUp() is False
assert posture.getPostureFamily() == "Crouching"
motion.wakeUp()
print("OK")
