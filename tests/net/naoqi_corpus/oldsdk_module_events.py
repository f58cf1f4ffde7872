"""Old SDK: ALBroker, an ALModule subclass called back by ALMemory.subscribeToEvent."""

import time

from _corpus import ip_port
from naoqi import ALBroker, ALModule, ALProxy

IP, PORT = ip_port()
broker = ALBroker("pythonBroker", "0.0.0.0", 0, IP, PORT)


class ReactToTouch(ALModule):
    """A module in the SDK examples' style."""

    def __init__(self, name):
        ALModule.__init__(self, name)
        self.touches = []
        self.words = []
        self.memory = ALProxy("ALMemory")  # through the broker
        self.memory.subscribeToEvent("FrontTactilTouched", "ReactToTouch", "onTouched")
        self.memory.subscribeToEvent("CorpusEvent", "ReactToTouch", "onEvent")

    def onTouched(self, strVarName, value):
        """Two arguments: the event's name and value."""
        self.touches.append((strVarName, value))

    def onEvent(self, key, value, message):
        """Three arguments: name, value and the subscriber's identifier."""
        self.words.append((key, value, message))


ReactToTouch = ReactToTouch("ReactToTouch")
memory = ALProxy("ALMemory", IP, PORT)
memory.raiseEvent("FrontTactilTouched", 1.0)
memory.raiseEvent("CorpusEvent", [1, "two"])
deadline = time.time() + 5
while (not ReactToTouch.touches or not ReactToTouch.words) and time.time() < deadline:
    time.sleep(0.01)
assert ReactToTouch.touches == [("FrontTactilTouched", 1.0)], ReactToTouch.touches
assert ReactToTouch.words == [("CorpusEvent", [1, "two"], "ReactToTouch")], ReactToTouch.words
memory.unsubscribeToEvent("FrontTactilTouched", "ReactToTouch")
memory.raiseEvent("FrontTactilTouched", 0.0)
time.sleep(0.3)
assert len(ReactToTouch.touches) == 1, "a callback after unsubscribeToEvent"
broker.shutdown()
print("OK")
