"""Errors are one RuntimeError line naming the method and the problem; nothing else."""

from _corpus import expect_error, session

s = session()
motion = s.service("ALMotion")
video = s.service("ALVideoDevice")
posture = s.service("ALRobotPosture")
texts = [
    expect_error(lambda: motion.moveTo("far", 0.0, 0.0), "ALMotion.moveTo"),
    expect_error(
        lambda: motion.setStiffnesses("Body", [0.5, 0.5]), "ALMotion.setStiffnesses", "26"
    ),
    expect_error(
        lambda: motion.angleInterpolation("HeadYaw", [0.1, 0.2], [0.5, 0.2], True), "increasing"
    ),
    expect_error(
        lambda: video.subscribeCamera("x", 7, 1, 11, 30),
        "ALVideoDevice.subscribeCamera",
        "camera index",
    ),
    expect_error(lambda: video.getResolution("ghost"), "ALVideoDevice.getResolution", "ghost"),
    expect_error(lambda: posture.goToPosture("Unknown", 0.5), "ALRobotPosture.goToPosture"),
]
for text in texts:
    assert not text.startswith("RuntimeError: RuntimeError"), text
    assert "At:" not in text and "/" not in text.split(":", 1)[0], text
services = s.services()
names = [info["name"] if isinstance(info, dict) else info for info in services]
assert "ALMotion" in names and "ALMemory" in names, names
print("OK")
