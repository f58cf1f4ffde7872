"""ALVideoDevice: the deprecated subscribe on the active camera, fps 1-30, parameters."""

from _corpus import expect_error, session

s = session()
video = s.service("ALVideoDevice")
assert video.setActiveCamera(1) is True
assert video.getActiveCamera() == 1
handle = video.subscribe("corpus_cam", 1, 11, 5)  # kQVGA, kRGB, 5 fps
try:
    image = video.getImageRemote(handle)
    width, height, layers, colorspace = image[0], image[1], image[2], image[3]
    assert (width, height, layers, colorspace) == (320, 240, 3, 11), image[:4]
    assert image[7] == 1, "not the bottom camera"
    assert len(image[6]) == width * height * layers
    assert video.releaseImage(handle) is True
    assert video.getFrameRate(handle) == 5
    assert handle in video.getSubscribers()
    odd = video.subscribeCamera("corpus_cam", 0, 0, 13, 7)  # any rate in 1-30
    assert odd != handle and video.getFrameRate(odd) == 7
    assert video.unsubscribe(odd) is True
    assert video.setParameter(0, 0, 100) is True  # brightness
    assert video.getParameter(0, 0) == 100
    assert video.setActiveCamera(5) is False
    expect_error(lambda: video.subscribeCamera("bad", 0, 1, 11, 31), "subscribeCamera", "fps")
    expect_error(lambda: video.getImageRemote("nobody"), "ALVideoDevice.getImageRemote", "nobody")
finally:
    assert video.unsubscribe(handle) is True
assert video.unsubscribe(handle) is False
video.setActiveCamera(0)
print("OK")
