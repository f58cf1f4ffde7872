"""Every module's ping, version, task model; the small companion services."""

from _corpus import expect_error, session

s = session()
for name in ["ALMotion", "ALVideoDevice", "ALRobotPosture", "ALMemory", "ALTextToSpeech",
             "ALLeds", "ALTouch", "ALAutonomousLife", "ALBasicAwareness", "ALBattery",
             "ALSystem", "ALSpeechRecognition", "ALAnimatedSpeech"]:  # fmt: skip
    service = s.service(name)
    assert service.ping() is True, name
    assert service.version().startswith("2."), name
    assert "ping" in service.getMethodList(), name
motion = s.service("ALMotion")
motion.wakeUp()
task = motion.pCall("moveTo", 0.5, 0.0, 0.0)
assert motion.isRunning(task)
assert motion.wait(task, 100) is False  # still walking after 0.1 s
motion.stop(task)
assert motion.wait(task, 5000) is True and not motion.isRunning(task)
system = s.service("ALSystem")
assert system.robotName() == "nao" and system.systemVersion().startswith("2.")
assert s.service("ALBattery").getBatteryCharge() == 100
life = s.service("ALAutonomousLife")
life.setState("disabled")
assert life.getState() == "disabled"
awareness = s.service("ALBasicAwareness")
awareness.setEngagementMode("FullyEngaged")
assert awareness.getEngagementMode() == "FullyEngaged"
awareness.stopAwareness()
assert awareness.isAwarenessRunning() is False
touch = s.service("ALTouch")
assert all(touched is False for _, touched, _ in touch.getStatus())
asr = s.service("ALSpeechRecognition")
asr.setLanguage("English")
asr.setVocabulary(["yes", "no"], False)
asr.subscribe("corpus")
assert s.service("ALMemory").getData("WordRecognized") == []
asr.unsubscribe("corpus")
expect_error(lambda: life.setState("dancing"), "ALAutonomousLife.setState", "dancing")
print("OK")
