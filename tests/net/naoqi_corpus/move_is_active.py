"""Poll moveIsActive() during an asynchronous moveTo; the future's value is True."""

import time

from _corpus import session

s = session()
motion = s.service("ALMotion")
motion.wakeUp()
future = motion.moveTo(0.3, 0.0, 0.0, _async=True)
seen_active = 0
deadline = time.time() + 60
while not future.isFinished():
    if motion.moveIsActive():
        seen_active += 1
    time.sleep(0.05)
    assert time.time() < deadline, "moveTo never ended"
assert seen_active > 3, f"moveIsActive() True only {seen_active} times during a 3 s walk"
assert future.value() is True
assert motion.moveIsActive() is False
task = motion.pCall("moveTo", 0.1, 0.0, 0.0)  # NAOqi 1 style post: a task id
assert motion.isRunning(task) is True
assert motion.wait(task, 0) is True and motion.isRunning(task) is False
print("OK", seen_active)
