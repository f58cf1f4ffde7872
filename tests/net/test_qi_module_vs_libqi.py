"""naoloc.qi behaves as the real qi package against a libqi server (issue 32, build item 4).

A real NAO runs libqi. A libqi server (the ``qi`` package serving on loopback, in a
subprocess) offers what NAO scripts meet: a dynamic signal and ALMemory-style
subscriber objects (events), a raw buffer, a struct with named fields, a property and
a failing method. One client script asks for each of them and prints what it got;
it is run with ``import qi`` and with ``import naoloc.qi as qi``, and the two outputs
must be the same, value for value and type for type.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from collections.abc import Iterator

import pytest

pytestmark = [
    pytest.mark.net,
    pytest.mark.skipif(
        importlib.util.find_spec("qi") is None,
        reason="the qi package (libqi) is not installed: no libqi server to test against",
    ),
]

SERVER = r"""
import sys, qi
qi.logging.setLevel(qi.logging.ERROR)

class Subscriber:
    def __init__(self):
        self.signal = qi.Signal("m")

class Memoryish:
    def __init__(self):
        self.changed = qi.Signal("m")
        self.pair = qi.Signal("(is)")
        self.level = qi.Property("i")
        self.subscribers = []
    @qi.bind(qi.Object, [qi.String])
    def subscriber(self, key):
        self.subscribers.append(Subscriber())
        return self.subscribers[-1]
    @qi.bind(qi.Void, [qi.Dynamic])
    def raiseEvent(self, value):
        self.changed(value)
        self.pair(3, "x")
        for s in self.subscribers:
            s.signal(value)
    @qi.bind("r", [qi.Int32])
    def buffer(self, n):
        return bytes(i % 251 for i in range(n))
    @qi.bind("(sid)<Landmark,name,id,size>", [])
    def landmark(self):
        return ("mark", 64, 0.09)
    @qi.bind("[(ss)<Pair,key,value>]", [])
    def pairs(self):
        return [("a", "b"), ("c", "d")]
    @qi.bind("(iirs)", [])
    def image(self):
        return (2, 1, b"\x01\x02", "plain tuple")
    @qi.bind(qi.Int32, [])
    def fail(self):
        raise RuntimeError("ALMemory: key does not exist")

session = qi.Session()
session.listenStandalone("tcp://127.0.0.1:0")
session.registerService("Memoryish", Memoryish())
print(session.endpoints()[0], flush=True)
sys.stdin.read()
"""

CLIENT = r"""
import importlib, os, sys, time
qi = importlib.import_module(os.environ["QI_MODULE"])
session = qi.Session()
session.connect(sys.argv[1])
m = session.service("Memoryish")
got = []
m.changed.connect(lambda *args: got.append(("changed", args)))
m.pair.connect(lambda *args: got.append(("pair", args)))
subscriber = m.subscriber("FrontTactilTouched")
subscriber.signal.connect(lambda value: got.append(("subscriber", value)))
m.level.connect(lambda *args: got.append(("level", args)))
for value in (1.0, [0.5, "x"], "text"):
    m.raiseEvent(value)
m.level.setValue(7)
deadline = time.time() + 3
while len(got) < 10 and time.time() < deadline:
    time.sleep(0.01)
for entry in sorted(got, key=repr):
    print("event", repr(entry))
print("level", repr(m.level.value()))
raw = m.buffer(5)
print("buffer", type(raw).__name__, repr(raw))
print("landmark", repr(m.landmark()))
print("pairs", repr(m.pairs()))
image = m.image()
print("image", type(image).__name__, [type(v).__name__ for v in image], repr(image))
try:
    m.fail()
except RuntimeError as err:
    print("error", repr(str(err)))
future = m.fail(_async=True)
future.wait(2000)
print("future", future.hasError(), repr(future.error()))
session.close()
"""


@pytest.fixture(scope="module")
def libqi_url() -> Iterator[str]:
    child = subprocess.Popen(
        [sys.executable, "-c", SERVER], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout is not None
        yield child.stdout.readline().strip()
    finally:
        assert child.stdin is not None
        child.stdin.close()
        child.wait(timeout=10)


def _client(module: str, url: str) -> list[str]:
    env = dict(os.environ, QI_MODULE=module)
    result = subprocess.run(
        [sys.executable, "-c", CLIENT, url],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
        check=False,
    )
    assert result.returncode == 0, f"{module}: {result.stdout}\n{result.stderr}"
    return result.stdout.splitlines()


@pytest.fixture(scope="module")
def outputs(libqi_url: str) -> dict[str, list[str]]:
    return {module: _client(module, libqi_url) for module in ("qi", "naoloc.qi")}


def test_the_real_qi_gives_what_nao_scripts_expect(outputs: dict[str, list[str]]) -> None:
    lines = outputs["qi"]
    assert "event ('subscriber', 1.0)" in lines  # the value itself, not [value]
    assert "event ('changed', (1.0,))" in lines
    assert "event ('pair', (3, 'x'))" in lines
    assert "event ('level', (7,))" in lines
    assert "buffer bytearray bytearray(b'\\x00\\x01\\x02\\x03\\x04')" in lines
    assert "landmark {'name': 'mark', 'id': 64, 'size': 0.09}" in lines
    assert "pairs [{'key': 'a', 'value': 'b'}, {'key': 'c', 'value': 'd'}]" in lines


@pytest.mark.parametrize(
    "what", ["event", "level", "buffer", "landmark", "pairs", "image", "error", "future"]
)
def test_naoloc_qi_gives_the_same_as_qi(outputs: dict[str, list[str]], what: str) -> None:
    theirs = [line for line in outputs["qi"] if line.split(" ", 1)[0] == what]
    ours = [line for line in outputs["naoloc.qi"] if line.split(" ", 1)[0] == what]
    assert theirs, f"qi printed no {what}"
    assert ours == theirs
