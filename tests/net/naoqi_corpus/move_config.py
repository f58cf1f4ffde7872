"""The moveConfig overloads of moveTo, move and moveToward."""

import time

from _corpus import expect_error, session, speed

s = session()
motion = s.service("ALMotion")
motion.wakeUp()
config = [["MaxStepX", 0.04], ["MaxStepFrequency", 1.0]]
assert motion.moveTo(0.2, 0.0, 0.0, config) is True
assert motion.moveTo([[0.1, 0.0, 0.0], [0.1, 0.1, 0.0]]) is True
assert motion.moveTo([[0.1, 0.0, 0.0]], config) is True
motion.move(0.05, 0.0, 0.0, config)
time.sleep(0.3 / speed())
assert motion.moveIsActive()
motion.moveToward(0.5, 0.0, 0.0, [["MaxStepX", 0.02]])
time.sleep(0.3 / speed())
motion.stopMove()
assert [row[0] for row in motion.getMoveConfig("Max")][:3] == [
    "MaxStepX",
    "MaxStepY",
    "MaxStepTheta",
]
expect_error(
    lambda: motion.moveTo(0.2, 0.0, 0.0, [["MaxStepZ", 1.0]]), "ALMotion.moveTo", "moveConfig"
)
expect_error(lambda: motion.moveTo(0.2, 0.0, 0.0, [["MaxStepX", 5.0]]), "MaxStepX")
expect_error(lambda: motion.moveToward(2.0, 0.0, 0.0), "moveToward", "[-1, 1]")
print("OK")
