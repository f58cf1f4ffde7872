"""Sleep-based walking: move(), sleep, stopMove(); the robot walks speed x time."""

import time

from _corpus import session, speed

s = session()
motion = s.service("ALMotion")
posture = s.service("ALRobotPosture")
motion.wakeUp()
posture.goToPosture("StandInit", 0.5)
x0 = motion.getRobotPosition(False)[0]
motion.move(0.1, 0.0, 0.0)
try:
    time.sleep(2.0 / speed())
    assert motion.moveIsActive(), "moveIsActive() False while walking"
finally:
    motion.stopMove()
walked = motion.getRobotPosition(False)[0] - x0
assert 0.15 < walked < 0.26, f"walked {walked:.3f} m in 2 s at 0.1 m/s"
motion.setAngles("HeadYaw", 1.0, 0.1)  # 0.83 rad/s: 1 rad takes 1.2 s
time.sleep(0.3 / speed())
yaw = motion.getAngles("HeadYaw", True)[0]
assert 0.1 < yaw < 0.6, f"HeadYaw at {yaw:.2f} rad after 0.3 s"
time.sleep(1.5 / speed())
assert abs(motion.getAngles("HeadYaw", True)[0] - 1.0) < 0.02
motion.setAngles("HeadYaw", 0.0, 1.0)
print("OK walked", round(walked, 3))
