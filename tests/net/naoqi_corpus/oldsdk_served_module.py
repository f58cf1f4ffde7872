"""Old SDK: a module one script serves is called by another script through ALProxy."""

import os
import subprocess
import sys
import time

from _corpus import ip_port
from naoqi import ALBroker, ALModule, ALProxy

IP, PORT = ip_port()
CALLER = """
import sys
from naoqi import ALProxy
counter = ALProxy("CorpusCounter", sys.argv[1], int(sys.argv[2]))
counter.add(2)
counter.add(3)
print("total", counter.total())
"""

broker = ALBroker("servingBroker", "0.0.0.0", 0, IP, PORT)


class CorpusCounter(ALModule):
    """Counts what other scripts add."""

    def __init__(self, name):
        ALModule.__init__(self, name)
        self.value = 0

    def add(self, n):
        """Add n."""
        self.value += n

    def total(self):
        """The sum so far."""
        return self.value


counter = CorpusCounter("CorpusCounter")
other = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"corpus_caller_{os.getpid()}.py")
with open(other, "w") as f:
    f.write(CALLER)
try:
    started = time.time()
    done = subprocess.run(
        [sys.executable, "-m", "naoloc.run", other, IP, str(PORT)],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
finally:
    os.remove(other)
assert done.returncode == 0, done.stderr
assert "total 5" in done.stdout, done.stdout
assert counter.value == 5
assert ALProxy("CorpusCounter").total() == 5  # this script's own module, through the broker
broker.shutdown()
print("OK")
