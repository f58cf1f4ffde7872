"""NaolocLocalization: learnHome, localize, getRobotPosition in the map frame, goToHome."""

import math

from _corpus import expect_error, session

s = session()
loc, sim, motion = s.service("NaolocLocalization"), s.service("NaolocSim"), s.service("ALMotion")
motion.wakeUp()
if not loc.isDataAvailable():
    expect_error(loc.localize, "learnHome")
    assert loc.learnHome() == 0
assert loc.isDataAvailable()
home = sim.true_pose()
motion.moveTo(0.5, 0.3, 0.5)
assert loc.localize() == 0
x, y, theta = loc.getRobotPosition()
tx, ty, _ = sim.true_pose()
# map frame: home is the origin, facing the map's +x
dx, dy = tx - home[0], ty - home[1]
c, s_ = math.cos(-home[2]), math.sin(-home[2])
truth = (c * dx - s_ * dy, s_ * dx + c * dy)
assert math.hypot(x - truth[0], y - truth[1]) < 0.3, ((x, y), truth)
assert loc.goToHome() == 0
hx, hy, _ = sim.true_pose()
assert math.hypot(hx - home[0], hy - home[1]) < 0.4, (hx - home[0], hy - home[1])
print("OK")
