"""Old SDK: ALProxy(name, ip, port), post, pCall, wait (0 = until the end), isRunning, stop."""

import time

from _corpus import ip_port, speed
from naoqi import ALProxy

IP, PORT = ip_port()
motion = ALProxy("ALMotion", IP, PORT)
posture = ALProxy("ALRobotPosture", IP, PORT)
tts = ALProxy("ALTextToSpeech", IP, PORT)
motion.wakeUp()
assert posture.goToPosture("StandInit", 0.5) is True
x0 = motion.getRobotPosition(False)[0]
task = motion.post.moveTo(0.2, 0.0, 0.0)
assert isinstance(task, int) and task > 0
assert motion.isRunning(task)
started = time.time()
assert motion.wait(task, 0) is True  # 0: until it ends
assert not motion.isRunning(task)
walked = motion.getRobotPosition(False)[0] - x0
assert 0.15 < walked < 0.25, f"walked {walked:.3f} m of 0.2"
assert (time.time() - started) * speed() > 1.0, "a 0.2 m walk ended at once"
task = motion.pCall("moveTo", 1.0, 0.0, 0.0)
assert motion.wait(task, 200) is False  # still walking
motion.stop(task)
assert motion.wait(task, 5000) is True
assert motion.walkTo(0.1, 0.0, 0.0) is True  # NAOqi 1.x names still work
motion.setWalkTargetVelocity(0.5, 0.0, 0.0, 1.0)
assert motion.walkIsActive()
motion.stopWalk()
said = tts.post.say("hello")  # a posted call of any module
tts.wait(said, 0)
names = motion.getBodyNames("Head")
assert names == ["HeadYaw", "HeadPitch"], names
try:
    motion.setAngles("Tail", 0.0, 0.5)
except RuntimeError as err:
    assert "Tail" in str(err)
else:
    raise AssertionError("setAngles('Tail') did not fail")
motion.rest()
print("OK")
