"""ALAnimationPlayer moves the joints; ALVideoRecorder writes a real video file."""

import os
import time

import cv2
from _corpus import expect_error, session, speed

s = session()
player, motion = s.service("ALAnimationPlayer"), s.service("ALMotion")
recorder = s.service("ALVideoRecorder")
motion.wakeUp()
started = time.time()
future = player.run("animations/Stand/Gestures/Hey_1", _async=True)
time.sleep(0.7 / speed())
raised = motion.getAngles("RShoulderPitch", True)[0]
future.value()
took = (time.time() - started) * speed()
assert raised < 0.0, f"the arm did not rise to wave: RShoulderPitch {raised:.2f}"
assert 2.0 < took < 6.0, f"the wave took {took:.1f} s"
started = time.time()
player.run("animations/Stand/Emotions/Positive/Happy_4")  # unknown: a 2 s no-op
assert (time.time() - started) * speed() > 1.5
player.runTag("yes")
recorder.setCameraID(0)
recorder.setResolution(1)
recorder.setFrameRate(10)
recorder.setVideoFormat("MJPG")
recorder.startRecording("/home/nao/recordings/cameras", "corpus", True)
assert recorder.isRecording()
time.sleep(1.0 / speed() + 0.3)
frames, path = recorder.stopRecording()
assert frames >= 5 and os.path.isfile(path), (frames, path)
video = cv2.VideoCapture(path)
ok, image = video.read()
assert ok and image.shape == (240, 320, 3), image.shape if ok else None
expect_error(lambda: recorder.startRecording("/../../etc", "x"), "may not leave")
expect_error(recorder.stopRecording, "not recording")
print("OK", frames, "frames")
