"""NAOqi's timing: moveToward with Frequency, re-sends answer at once, wait(id, 0), postures."""

import time

from _corpus import session, speed

s = session()
motion, posture = s.service("ALMotion"), s.service("ALRobotPosture")
motion.wakeUp()
posture.goToPosture("StandInit", 0.5)
motion.moveToward(0.5, 0.0, 0.0, [["Frequency", 1.0]])  # the SDK examples' walk
try:
    slowest = 0.0
    for _ in range(10):
        started = time.time()
        motion.moveToward(0.5, 0.0, 0.0, [["Frequency", 1.0]])
        slowest = max(slowest, time.time() - started)
        time.sleep(0.05)
    assert slowest < 0.1, f"a moveToward re-send took {slowest:.3f} s"
    time.sleep(0.5 / speed())
    assert motion.moveIsActive()
finally:
    motion.stopMove()
task = motion.pCall("moveTo", 0.3, 0.0, 0.0)
started = time.time()
assert motion.wait(task, 0) is True  # 0: until the walk ends
assert (time.time() - started) * speed() > 1.0, "wait(id, 0) returned before the walk ended"
started = time.time()
assert posture.goToPosture("Sit", 0.5) is True
sat = (time.time() - started) * speed()
assert sat > 3.0, f"Sit took {sat:.1f} s; a NAO takes seconds"
started = time.time()
motion.rest()
assert (time.time() - started) * speed() > 1.0
started = time.time()
motion.wakeUp()
assert (time.time() - started) * speed() > 1.5
print("OK sit", round(sat, 1), "s")
