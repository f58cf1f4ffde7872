"""A second client's stopMove ends a blocking moveTo at once; moveTo returns False."""

import threading
import time

from _corpus import session, speed

walker = session()
stopper = session()
motion = walker.service("ALMotion")
motion.wakeUp()
result: list[object] = []


def walk() -> None:
    result.append(motion.moveTo(2.0, 0.0, 0.0))  # 20 s of walking
    result.append(time.time())


thread = threading.Thread(target=walk)
thread.start()
time.sleep(1.0 / speed())
assert motion.moveIsActive() is True
head = stopper.service("ALMotion")
t0 = time.time()
head.angleInterpolationWithSpeed("HeadYaw", 1.0, 0.5)  # 1 rad at 4.1 rad/s: 0.25 s
assert (time.time() - t0) * speed() < 2.0, "a blocking head move waited for the walk"
assert motion.moveIsActive() is True, "the head move ended the walk"
head.angleInterpolationWithSpeed("HeadYaw", 0.0, 1.0)
stopped_at = time.time()
stopper.service("ALMotion").stopMove()
thread.join(10)
assert not thread.is_alive(), "moveTo still blocks after another client's stopMove"
assert result[0] is False, f"moveTo returned {result[0]!r} after stopMove"
assert float(result[1]) - stopped_at < 0.5, (
    f"moveTo returned {float(result[1]) - stopped_at:.2f} s late"
)
walked = motion.getRobotPosition(False)[0]
killer_session = session()  # keep the session: a dropped one disconnects
killer = killer_session.service("ALMotion")
future = motion.moveTo(1.0, 0.0, 0.0, _async=True)
time.sleep(0.5 / speed())
killer.killMove()
assert future.value() is False
assert motion.moveIsActive() is False
print("OK stopped after", round(walked, 3), "m")
