"""The most-used ALMotion methods beyond walking, with NAOqi's arguments and results."""

import time

from _corpus import expect_error, session, speed

s = session()
motion = s.service("ALMotion")
motion.wakeUp()
assert len(motion.getBodyNames("Body")) == 26
assert len(motion.getBodyNames("JointActuators")) == 25
assert motion.getBodyNames("Head") == ["HeadYaw", "HeadPitch"]
motion.setMoveArmsEnabled(False, True)
assert motion.getMoveArmsEnabled("LArm") is False and motion.getMoveArmsEnabled("RArm") is True
assert motion.setCollisionProtectionEnabled("Arms", True) is True
motion.setExternalCollisionProtectionEnabled("All", False)
assert motion.getExternalCollisionProtectionEnabled("Move") is False
motion.setExternalCollisionProtectionEnabled("All", True)
motion.setMotionConfig([["ENABLE_FOOT_CONTACT_PROTECTION", True]])
motion.wbEnable(False)  # not simulated: accepted
t0 = time.time()
motion.angleInterpolation(["HeadYaw", "HeadPitch"], [[0.5, 0.0], [0.2]], [[0.5, 1.0], [0.5]], True)
took = (time.time() - t0) * speed()
assert 0.9 < took < 1.6, f"angleInterpolation of 1 s took {took:.2f} s"
yaw, pitch = motion.getAngles("Head", True)
assert abs(yaw) < 0.03 and abs(pitch - 0.2) < 0.03, (yaw, pitch)
motion.setAngles(["HeadYaw", "HeadPitch"], [0.3, 0.0], [0.5, 0.2])  # per-joint speeds
motion.stiffnessInterpolation("Head", [0.5], [0.2])
assert motion.getStiffnesses("Head") == [0.5, 0.5]
motion.setStiffnesses("Head", 1.0)
motion.openHand("LHand")
assert motion.getAngles("LHand", True)[0] > 0.9
motion.closeHand("LHand")
assert motion.getAngles("LHand", True)[0] < 0.1
summary = motion.getSummary()
assert "HeadYaw" in summary and "Tasks" in summary
motion.transformInterpolations("LArm", 2, [[1.0] * 6], 63, [0.2])  # not simulated: blocks
motion.move(0.05, 0.0, 0.0)
time.sleep(0.2 / speed())
motion.killMove()
assert motion.moveIsActive() is False
motion.killAll()
assert motion.stopMove() is True
expect_error(lambda: motion.setAngles("Tail", 0.0, 0.5), "ALMotion.setAngles", "Tail")
expect_error(lambda: motion.setAngles("HeadYaw", 0.0, 2.0), "(0, 1]")
expect_error(lambda: motion.openHand("LFoot"), "ALMotion.openHand", "LFoot")
print("OK")
