"""ALFaceDetection, ALTracker, ALLandMarkDetection: documented stand-ins that see nothing."""

from _corpus import expect_error, session

s = session()
memory, motion = s.service("ALMemory"), s.service("ALMotion")
faces, marks = s.service("ALFaceDetection"), s.service("ALLandMarkDetection")
tracker = s.service("ALTracker")
faces.subscribe("corpus", 500, 0.0)
assert memory.getData("FaceDetected") == []
assert faces.learnFace("someone") is False and faces.getLearnedFacesList() == []
faces.setTrackingEnabled(True)
assert faces.isTrackingEnabled() is True
faces.unsubscribe("corpus")
marks.subscribe("corpus")
assert memory.getData("LandmarkDetected") == []
marks.unsubscribe("corpus")
tracker.registerTarget("Face", 0.15)
tracker.setMode("Head")
tracker.track("Face")
assert tracker.isActive() and tracker.isTargetLost() and tracker.getTargetPosition() == []
tracker.stopTracker()
tracker.unregisterAllTargets()
expect_error(lambda: tracker.track("Face"), "ALTracker.track", "registerTarget")
motion.wakeUp()
tracker.lookAt([1.0, 1.0, 0.4], 2, 0.5, False)  # FRAME_ROBOT: ahead and to the left
yaw = motion.getAngles("HeadYaw", True)[0]
assert 0.5 < yaw < 1.1, yaw
tracker.lookAt([1.0, 0.0, 0.45], 2, 0.5, False)
print("OK")
