"""ALSonar (values and events while subscribed) and the inertial ALMemory keys."""

import math
import time

from _corpus import keep_place, session, speed

s = session()
memory, sonar, sim = s.service("ALMemory"), s.service("ALSonar"), s.service("NaolocSim")
back = keep_place(s)
width, depth = sim.room_size()
sim.teleport(width / 2, 0.8, -math.pi / 2)  # facing the wall 0.8 m away
LEFT = "Device/SubDeviceList/US/Left/Sensor/Value"
RIGHT = "Device/SubDeviceList/US/Right/Sensor/Value"
sonar.subscribe("corpus")
try:
    time.sleep(0.5 / speed() + 0.2)
    left, right = memory.getData(LEFT), memory.getData(RIGHT)
    # a cone +-30 deg around 25 deg off the axis: the nearest wall point is ~0.8 m away
    assert 0.7 < left < 1.0 and 0.7 < right < 1.0, (left, right)
    assert LEFT in sonar.getOutputNames()
    sim.teleport(width / 2, 0.4, -math.pi / 2)  # nearer than 0.5 m: the Detected events
    time.sleep(0.5 / speed() + 0.2)
    assert memory.getData(LEFT) < 0.5, memory.getData(LEFT)
    assert memory.getData("SonarLeftDetected") < 0.5
finally:
    sonar.unsubscribe("corpus")
back()  # where the other scripts expect the robot
for key in ("AngleX", "AngleY", "AngleZ", "GyrX", "GyrY", "AccX", "AccY", "AccZ"):
    value = memory.getData(f"Device/SubDeviceList/InertialSensor/{key}/Sensor/Value")
    assert isinstance(value, float), (key, value)
acc_z = memory.getData("Device/SubDeviceList/InertialSensor/AccZ/Sensor/Value")
assert -10.0 < acc_z < -9.0, acc_z  # gravity, as a standing NAO reads it
angle_x = memory.getData("Device/SubDeviceList/InertialSensor/AngleX/Sensor/Value")
assert abs(angle_x) < 0.2, angle_x
print("OK")
