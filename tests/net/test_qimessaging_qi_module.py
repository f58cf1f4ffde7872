"""``import naoloc.qi as qi``: NAO scripts run with the real qi package blocked from import.

A script in qi's style (Application with ``--qi-url``, service proxies, ``_async=True``
futures, Promise, Signal, RuntimeError on remote errors) runs in a subprocess where
``import qi`` fails, against ``naoloc serve`` over zmq, over qimessaging and (where
installed) over libqi.
"""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
import time

import pytest

import naoloc.qi as nqi
from naoloc.backends.naoqi.testing import served

pytestmark = pytest.mark.net

FAKE = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [4.0, 4.0], "seed": 3}}}
SERVERS = [
    "zmq",
    "qimessaging",
    pytest.param(
        "libqi",
        marks=pytest.mark.skipif(importlib.util.find_spec("qi") is None, reason="qi not installed"),
    ),
]

SCRIPT = r"""
import importlib.abc, json, sys, time

class BlockQi(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name == "qi" or name.startswith("qi."):
            raise ImportError("No module named 'qi' (blocked)")
        return None

sys.meta_path.insert(0, BlockQi())
try:
    import qi
    raise SystemExit("the real qi imported")
except ImportError:
    import naoloc.qi as qi

app = qi.Application(sys.argv[:1] + ["--qi-url", sys.argv[1], "--other"])
app.start()
session = app.session
motion = session.service("ALMotion")
posture = session.service("ALRobotPosture")
video = session.service("ALVideoDevice")
out = {}
motion.wakeUp()
out["posture"] = posture.goToPosture("StandInit", 0.5)
future = motion.moveTo(0.2, 0.0, 0.0, _async=True)
out["future_type"] = type(future).__name__
out["moved"] = future.value(30000)
out["state"] = future.wait(0)
out["pose"] = [round(v, 2) for v in motion.getRobotPosition(False)]
handle = video.subscribeCamera("script", 0, 1, 11, 5)
image = video.getImageRemote(handle)
out["image"] = [image[0], image[1], len(image[6])]
video.unsubscribe(handle)
try:
    video.getImageRemote("nope")
    out["error"] = None
except RuntimeError as err:
    out["error"] = str(err)
failed = video.getImageRemote("nope", _async=True)
out["has_error"] = failed.hasError(5000)
promise = qi.Promise()
seen = []
promise.future().addCallback(lambda f: seen.append(f.value()))
promise.setValue(42)
signal = qi.Signal()
link = signal.connect(lambda x: seen.append(x))
signal("fired")
signal.disconnect(link)
signal("not seen")
out["seen"] = seen
out["services"] = sorted(s["name"] for s in session.services() if s["name"].startswith("AL"))
out["qi_module"] = qi.__name__
session.close()
print(json.dumps(out))
"""


@pytest.mark.parametrize("transport", SERVERS)
def test_a_qi_style_script_runs_with_qi_blocked(transport: str) -> None:
    with served(FAKE, transport) as server:
        ran = subprocess.run(
            [sys.executable, "-c", SCRIPT, server.url], capture_output=True, text=True, timeout=120
        )
    assert ran.returncode == 0, ran.stderr[-2000:]
    out = json.loads(ran.stdout.strip().splitlines()[-1])
    assert out["qi_module"] == "naoloc.qi"
    assert out["posture"] is True and out["moved"] is True
    assert out["future_type"] == "Future" and out["state"] == "FinishedWithValue"
    assert out["pose"][0] == pytest.approx(0.2, abs=0.03)
    assert out["image"] == [320, 240, 320 * 240 * 3]
    assert out["error"] is not None and "HandleError" in out["error"]
    assert "\n" not in out["error"] and out["has_error"] is True
    assert out["seen"] == [42, "fired"]
    assert {"ALMotion", "ALRobotPosture", "ALVideoDevice"} <= set(out["services"])


def test_application_is_a_singleton_and_parses_qi_url() -> None:
    nqi.Application._reset_for_tests()
    argv = ["prog", "--qi-url=tcp://10.0.0.2:9559", "--keep"]
    try:
        app = nqi.Application(argv)
        assert app.url == "tcp://10.0.0.2:9559" and argv == ["prog", "--keep"]
        with pytest.raises(RuntimeError, match="already"):
            nqi.Application(["prog"])
    finally:
        nqi.Application._reset_for_tests()
    app = nqi.Application(["prog"], url="tcp://127.0.0.1:1")
    try:
        assert app.url == "tcp://127.0.0.1:1"
        with pytest.raises(RuntimeError, match="no NAOqi answers"):
            app.start()  # nothing listens on port 1: one line, no traceback from inside
    finally:
        nqi.Application._reset_for_tests()


def test_zmq_scheme_forces_zmq() -> None:
    with served(FAKE, "zmq") as server:
        session = nqi.Session()
        session.connect(server.url.replace("tcp://", "zmq://"))
        try:
            assert type(session._session).__name__ == "ZmqSession"
            assert session.service("ALMotion").getRobotPosition(True) == [0.0, 0.0, 0.0]
        finally:
            session.close()


def test_periodic_tasks_run_async_and_loggers() -> None:
    calls: list[float] = []
    task = nqi.PeriodicTask()
    task.setCallback(lambda: calls.append(1.0))
    task.setUsPeriod(20_000)
    task.start(True)
    try:
        deadline = time.monotonic() + 2
        while len(calls) < 3 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert task.isRunning() and len(calls) >= 3
    finally:
        task.stop()
    count = len(calls)
    time.sleep(0.1)
    assert not task.isRunning() and len(calls) == count
    assert nqi.runAsync(lambda a, b: a + b, 2, 3).value(2000) == 5
    failing = nqi.runAsync(lambda: 1 / 0)
    assert failing.hasError(2000) and "ZeroDivisionError" in failing.error()
    nqi.logging.setLevel(nqi.logging.ERROR)
    nqi.Logger("script").info("not shown")  # no error: qi's logger shape
