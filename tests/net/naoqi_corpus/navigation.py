"""ALNavigation: navigateTo around the room's obstacles, moveAlong Line and Circle."""

import math

from _corpus import expect_error, keep_place, session

s = session()
nav, sim, motion = s.service("ALNavigation"), s.service("NaolocSim"), s.service("ALMotion")
motion.wakeUp()
back = keep_place(s)
width, depth = sim.room_size()
sim.teleport(width / 2 - 1.0, depth / 2, 0.0)
x0, y0, _ = sim.true_pose()
assert nav.navigateTo(1.2, 0.6) is True
x1, y1, _ = sim.true_pose()
assert math.hypot(x1 - x0 - 1.2, y1 - y0 - 0.6) < 0.2, (x1 - x0, y1 - y0)
assert nav.navigateTo(width + 2.0, 0.0) is False  # beyond the wall: as near as it can
sim.teleport(width / 2, depth / 2, 0.0)
x1, y1, _ = sim.true_pose()
assert nav.moveAlong(["Holonomic", ["Line", [0.3, 0.0]], 0.0, 5.0]) is True
x2, y2, _ = sim.true_pose()
assert 0.2 < math.hypot(x2 - x1, y2 - y1) < 0.4, (x2 - x1, y2 - y1)
trajectory = ["Composed", ["Holonomic", ["Line", [0.2, 0.0]], 0.0, 5.0],
              ["Holonomic", ["Circle", [0.0, 0.3], 1.0], 0.0, 5.0]]  # fmt: skip
assert nav.moveAlong(trajectory) is True
expect_error(lambda: nav.moveAlong(["Spiral", 1]), "ALNavigation.moveAlong")
back()  # where the other scripts expect the robot
nav.setSecurityDistance(0.3)
assert abs(nav.getSecurityDistance() - 0.3) < 1e-9
print("OK")
