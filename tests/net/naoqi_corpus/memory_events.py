"""ALMemory: data, standard keys, joint sensor keys, and events delivered to every client."""

import threading
import time

from _corpus import expect_error, session, speed

a, b, c = session(), session(), session()
got: dict[str, list[object]] = {"a": [], "b": []}
done = threading.Event()


def listener(name: str):
    def on_event(value: object) -> None:
        got[name].append(value)
        if all(got.values()):
            done.set()

    return on_event


sub_a = a.service("ALMemory").subscriber("CorpusEvent")
sub_a.signal.connect(listener("a"))
sub_b = b.service("ALMemory").subscriber("CorpusEvent")
sub_b.signal.connect(listener("b"))
memory = c.service("ALMemory")
memory.raiseEvent("CorpusEvent", [1, "two", 3.0])
assert done.wait(5), f"events delivered: {got}"
assert got["a"][0] == [1, "two", 3.0] and got["b"][0] == [1, "two", 3.0], got
memory.insertData("corpus/key", 42)
assert memory.getData("corpus/key") == 42
assert "corpus/key" in memory.getDataList("corpus")
assert memory.getData("robotHasFallen") == 0
motion = c.service("ALMotion")
motion.wakeUp()
motion.angleInterpolationWithSpeed("HeadYaw", 0.5, 1.0)
time.sleep(0.1 / speed())
yaw = memory.getData("Device/SubDeviceList/HeadYaw/Position/Sensor/Value")
assert abs(yaw - 0.5) < 0.02, yaw
assert memory.getData("Device/SubDeviceList/HeadYaw/Hardness/Actuator/Value") == 1.0
assert "Device/SubDeviceList/HeadYaw/Position/Sensor/Value" in memory.getDataListName()
expect_error(lambda: memory.getData("no/such/key"), "ALMemory.getData", "no/such/key")
motion.setAngles("HeadYaw", 0.0, 1.0)
failures: list[object] = []
failed = threading.Event()
sub_fail = a.service("ALMemory").subscriber("ALMotion/MoveFailed")
sub_fail.signal.connect(lambda value: (failures.append(value), failed.set()))
start = motion.getRobotPosition(False)[0]
assert motion.moveTo(-3.0, 0.0, 0.0) is False  # backwards into the wall behind
assert failed.wait(5), "no ALMotion/MoveFailed event"
assert failures[0][0] == "Internal stop" and len(failures[0][2]) == 3, failures
assert motion.moveTo(start - motion.getRobotPosition(False)[0], 0.0, 0.0) is True  # back
print("OK")
