"""ALTextToSpeech and ALAnimatedSpeech: say blocks for a plausible time."""

import time

from _corpus import expect_error, session, speed

s = session()
tts = s.service("ALTextToSpeech")
assert "English" in tts.getAvailableLanguages()
tts.setLanguage("English")
assert tts.getLanguage() == "English"
tts.setVolume(0.5)
assert abs(tts.getVolume() - 0.5) < 1e-6
text = "Hello, I am a simulated NAO and I speak at about two words a second"
t0 = time.time()
tts.say(text)
took = (time.time() - t0) * speed()
words = len(text.split())
assert 0.25 * words < took < 0.8 * words + 1.0, f"{words} words in {took:.2f} s"
s.service("ALAnimatedSpeech").say("^start(animations/Stand/Gestures/Hey_1) Hello!")
expect_error(lambda: tts.setLanguage("Klingon"), "ALTextToSpeech.setLanguage", "Klingon")
expect_error(lambda: tts.setVolume(3.0), "volume")
print("OK", round(took, 2), "s")
