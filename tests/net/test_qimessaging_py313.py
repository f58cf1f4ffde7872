"""The libqi-free fallback on a Python the qi package has no wheel for (3.13).

Runs ``import naoloc.qi`` and naoloc's QiMessaging client and server under Python
3.13 with ``qi`` blocked from import, in a small venv of naoloc's import-time
dependencies (numpy, pydantic, PyYAML; made once per machine in the temp folder);
it talks to a ``naoloc serve --transport qimessaging`` of this checkout, to a server
of its own and, where qi is installed here, to a real libqi server. Skipped, with
the reason, where no Python 3.13 is found or its venv cannot be made (offline).
"""

from __future__ import annotations

import glob
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib
from collections.abc import Iterator
from pathlib import Path

import pytest

from naoloc.backends.naoqi.testing import served

pytestmark = pytest.mark.net

ROOT = Path(__file__).resolve().parents[2]
FAKE = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [4.0, 4.0], "seed": 3}}}
NEEDED = ("numpy", "pydantic", "pyyaml")  # what `import naoloc` needs at import time

SCRIPT = r"""
import importlib.abc, json, sys, time

class BlockQi(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name == "qi" or name.startswith("qi."):
            raise ImportError("qi is blocked for this test")
        return None

sys.meta_path.insert(0, BlockQi())
import naoloc.qi as qi
import naoloc
from naoloc.backends.naoqi.session import resolve_transport

report = {"python": sys.version.split()[0], "auto": resolve_transport("auto")}

class Twice:
    def __init__(self):
        self.changed = qi.Signal("(i)")
    @qi.bind(qi.Int32, [qi.Int32])
    def twice(self, x):
        self.changed(x)
        return 2 * x

server = qi.Session()
server.listenStandalone("tcp://127.0.0.1:0")
server.registerService("Twice", Twice())
client = qi.Session()
client.connect(server.endpoints()[0])
got = []
client.service("Twice").changed.connect(got.append)
report["own"] = client.service("Twice").twice(21)
time.sleep(0.2)
report["signal"] = got
client.close()
server.close()

app = qi.Application(["script", "--qi-url", sys.argv[1]])
app.start()
motion = app.session.service("ALMotion")
report["pose"] = motion.getRobotPosition(True)
report["moved"] = motion.moveTo(0.1, 0.0, 0.0)
app.session.close()

cfg = {"robot": {"backend": "naoqi", "url": sys.argv[1], "transport": "auto"}}
with naoloc.connect(cfg) as robot:
    report["robot_transport"] = robot.info["transport"]
    handle = robot.video.subscribeCamera("py313", 0, 1, 11, 30)
    frame = robot.video.getImageRemote(handle)
    report["frame"] = [frame[0], frame[1], len(frame[6])]

if len(sys.argv) > 2:
    libqi = qi.Session()
    libqi.connect(sys.argv[2])
    report["libqi"] = libqi.service("QimTest").echo0(7)
    libqi.close()
report["qi_imported"] = "qi" in sys.modules
print(json.dumps(report))
"""


def _python313() -> str | None:
    """A working Python 3.13 (pyenv shims that refuse to run are passed over)."""
    home = os.environ.get("PYENV_ROOT", os.path.expanduser("~/.pyenv"))
    candidates = sorted(glob.glob(f"{home}/versions/3.13*/bin/python3.13"))
    candidates += [found] if (found := shutil.which("python3.13")) else []
    for candidate in candidates:
        check = [candidate, "-c", "import sys; print(sys.version_info[:2] == (3, 13))"]
        try:
            ran = subprocess.run(check, capture_output=True, text=True, timeout=30)
        except OSError:
            continue
        if ran.returncode == 0 and ran.stdout.strip() == "True":
            return candidate
    return None


def _pins() -> list[str]:
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    pins = [d for d in deps if re.split(r"[=<>~ ;]", d, maxsplit=1)[0].lower() in NEEDED]
    assert len(pins) == len(NEEDED), pins
    return pins


@pytest.fixture(scope="module")
def python313() -> Iterator[str]:
    base = _python313()
    if base is None:
        pytest.skip("no Python 3.13 on this machine (python3.13 or ~/.pyenv/versions/3.13*)")
    pins = _pins()
    key = "-".join(p.replace("==", "") for p in pins)
    venv = Path(tempfile.gettempdir()) / f"naoloc-py313-{os.getuid()}-{key}"
    python = venv / "bin" / "python"
    if not python.exists():
        building = Path(tempfile.mkdtemp(prefix="naoloc-py313-build-"))
        made = subprocess.run([base, "-m", "venv", str(building)], capture_output=True)
        pip = [str(building / "bin" / "python"), "-m", "pip", "install", "-q", *pins]
        installed = (
            made.returncode == 0 and subprocess.run(pip, capture_output=True).returncode == 0
        )
        if not installed:
            shutil.rmtree(building, ignore_errors=True)
            pytest.skip(f"cannot make a Python 3.13 venv with {', '.join(pins)} (offline?)")
        try:
            building.rename(venv)
        except OSError:  # another run made it first
            shutil.rmtree(building, ignore_errors=True)
        # venv scripts hold absolute paths; the interpreter itself does not care.
    yield str(python)


def test_naoloc_qi_runs_on_python_313_without_qi(python313: str) -> None:
    import json

    args = [python313, "-c", SCRIPT]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONNOUSERSITE": "1"}
    env.pop("PYTHONHOME", None)
    with served(FAKE, "qimessaging") as server:
        args.append(server.url)
        libqi_child = None
        if importlib.util.find_spec("qi") is not None:
            from test_qimessaging_interop import LIBQI_SERVICE

            cmd = [sys.executable, "-c", LIBQI_SERVICE, "i"]
            libqi_child = subprocess.Popen(
                cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
            )
            assert libqi_child.stdout is not None
            args.append(libqi_child.stdout.readline().strip())
        try:
            result = subprocess.run(args, capture_output=True, text=True, env=env, timeout=120)
        finally:
            if libqi_child is not None:
                assert libqi_child.stdin is not None
                libqi_child.stdin.close()
                libqi_child.wait(timeout=10)
    assert result.returncode == 0, result.stderr[-2000:]
    report = json.loads(result.stdout.strip().splitlines()[-1])
    assert report["python"].startswith("3.13")
    assert report["auto"] == "qimessaging" and report["robot_transport"] == "qimessaging"
    assert report["own"] == 42 and report["signal"] == [21]
    assert report["pose"] == [0.0, 0.0, 0.0] and report["moved"] is True
    assert report["frame"] == [320, 240, 320 * 240 * 3]
    assert report["qi_imported"] is False
    if len(args) > 4:
        assert report["libqi"] == 7


def test_the_naoqi_extra_never_requires_qi_where_it_has_no_wheel() -> None:
    requirements = pytest.importorskip("packaging.requirements")
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"
    ]
    (qi_req,) = [requirements.Requirement(r) for r in extras["naoqi"] if r.startswith("qi")]
    assert qi_req.marker is not None
    linux = {"sys_platform": "linux", "platform_machine": "x86_64", "python_version": "3.12"}
    assert qi_req.marker.evaluate(linux)
    for other in (
        {"python_version": "3.13"},
        {"sys_platform": "darwin", "platform_machine": "arm64"},
        {"sys_platform": "win32", "platform_machine": "AMD64"},
        {"platform_machine": "aarch64"},
    ):
        assert not qi_req.marker.evaluate({**linux, **other}), other
