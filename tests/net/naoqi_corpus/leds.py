"""ALLeds: fadeRGB blocks for its duration; on/off; groups."""

import time

from _corpus import expect_error, session, speed

s = session()
leds = s.service("ALLeds")
t0 = time.time()
leds.fadeRGB("FaceLeds", 0x00FF00, 1.0)
took = (time.time() - t0) * speed()
assert 0.9 < took < 1.6, f"fadeRGB of 1 s took {took:.2f} s"
assert leds.getRGB("LeftFaceLeds") == 0x00FF00
leds.fadeRGB("ChestLeds", "red", 0.2)
assert leds.getRGB("ChestLeds") == 0xFF0000
leds.off("EarLeds")
assert leds.getIntensity("LeftEarLeds") == 0.0
leds.on("EarLeds")
assert leds.getIntensity("RightEarLeds") == 1.0
assert "FaceLeds" in leds.listGroups() and "AllLeds" in leds.listGroups()
leds.createGroup("CorpusGroup", ["ChestLeds", "LeftEarLeds"])
leds.fadeRGB("CorpusGroup", 0.0, 0.0, 1.0, 0.1)
assert leds.getRGB("LeftEarLeds") == 0x0000FF
leds.rasta(0.2)
expect_error(lambda: leds.on("NoseLeds"), "ALLeds.on", "NoseLeds")
print("OK")
