"""Issue 34, items 1 and 9: serve's login policy, and inputs that are not what they claim.

Only regular files are read and written (a FIFO, a device or a folder gets one line and
exit 1, never a hang or a replaced device node), config values keep to sane ranges
(no boolean for a number, no duplicate key, no 10**12 count), and ``naoloc serve``
takes its password from the environment or a prompt, never from the command line.
"""

from __future__ import annotations

import os
import stat
import threading
from pathlib import Path

import pytest

from naoloc.app.cli import main
from naoloc.app.commands.serve import check_listen, read_login
from naoloc.config import load_config
from naoloc.errors import BackendError, ConfigError


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """``naoloc ARGV`` in-process, failing (not hanging) when it does not end in 20 s."""
    result: list[int] = []
    thread = threading.Thread(target=lambda: result.append(main(argv)), daemon=True)
    thread.start()
    thread.join(20)
    assert result, f"naoloc {' '.join(argv)} hung"
    return result[0], capsys.readouterr().err.strip()


@pytest.fixture
def fifo(tmp_path: Path) -> Path:
    path = tmp_path / "pipe"
    os.mkfifo(path)
    return path


@pytest.fixture
def fake(tmp_path: Path) -> Path:
    path = tmp_path / "fake.yaml"
    path.write_text("robot: {backend: fake}\n")
    return path


@pytest.mark.parametrize("flag", ["-c", "-m", "-d"])
def test_a_fifo_as_input_is_refused_at_once(
    flag: str, fifo: Path, fake: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = {
        "-c": ["localize", "-c", str(fifo), "-m", str(tmp_path / "m.npz")],
        "-m": ["localize", "-c", str(fake), "-m", str(fifo)],
        "-d": ["build-map", "-c", str(fake), "-d", str(fifo), "-o", str(tmp_path / "m.npz")],
    }[flag]
    code, err = _run(argv, capsys)
    assert code == 1 and len(err.splitlines()) == 1 and "is a FIFO" in err


def test_a_device_is_never_read_as_a_map_nor_replaced_by_an_output(
    fake: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, err = _run(["localize", "-c", str(fake), "-m", "/dev/zero"], capsys)
    assert code == 1 and "is a character device, not a map file" in err
    code, err = _run(["survey", "-c", str(fake), "-o", "/dev/null"], capsys)
    assert code == 1 and "naoloc writes only regular files" in err
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)


def test_a_folder_output_is_refused(fake: Path, tmp_path: Path) -> None:
    from naoloc.data.outputs import staged

    with pytest.raises(ConfigError, match="is a folder"), staged(tmp_path):
        pass


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("survey: {step_m: true}\n", "survey.step_m: a number is expected, got a boolean"),
        ("survey: {laps: 1}\nsurvey: {laps: 2}\n", "the key 'survey' appears twice"),
        ("world: {sim: {timestep_s: 1.0e-12}}\n", "world.sim.timestep_s"),
        ("localize: {filter: {pnp_iterations: 1000000000000}}\n", "is over 1000000"),
        ("world: {room: {size_m: [true, 4.0]}}\n", "a number is expected"),
    ],
)
def test_config_values_out_of_sense_are_refused(text: str, problem: str, tmp_path: Path) -> None:
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=problem.replace("(", r"\(")):
        load_config(path)


@pytest.mark.parametrize("args", [["-n", "1e12"], ["-n", "1000000000000"], ["--workers", "0"]])
def test_evaluate_counts_are_usage_errors(args: list[str], tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["evaluate", "-c", "paper_room", "-o", str(tmp_path / "e"), *args])
    assert exit_.value.code == 2


def test_qimessaging_off_loopback_needs_a_login_and_tls() -> None:
    check_listen("tcp://127.0.0.1:0", "qimessaging", False, None)
    with pytest.raises(BackendError, match="needs a login and TLS"):
        check_listen("tcp://0.0.0.0:9559", "qimessaging", True, None)
    with pytest.raises(BackendError, match="needs a login and TLS"):
        check_listen("tcp://0.0.0.0:9559", "qimessaging", True, None, login=True)
    with pytest.raises(BackendError, match="needs a certificate"):
        check_listen("tcps://0.0.0.0:9503", "qimessaging", True, None, login=True)
    check_listen("tcps://0.0.0.0:9503", "qimessaging", True, None, login=True, tls=True)
    with pytest.raises(BackendError, match="tcp://HOST:PORT"):
        check_listen("tcps://127.0.0.1:0", "zmq", False, None)


def test_the_password_comes_from_the_environment_or_a_terminal(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv("NAOLOC_SERVE_PASSWORD", raising=False)
    monkeypatch.delenv("NAOLOC_SERVE_USER", raising=False)
    assert read_login(False) is None
    with open(os.devnull) as no_terminal:  # nothing to ask on
        monkeypatch.setattr("sys.stdin", no_terminal)
        with pytest.raises(ConfigError, match="NAOLOC_SERVE_PASSWORD"):
            read_login(True)
    monkeypatch.setenv("NAOLOC_SERVE_PASSWORD", "pw")
    assert read_login(False) == {"nao": "pw"}  # a password in the environment asks a login
    monkeypatch.setenv("NAOLOC_SERVE_USER", "admin")
    assert read_login(True) == {"admin": "pw"}
    monkeypatch.setenv("NAOLOC_SERVE_PASSWORD", "")
    with pytest.raises(ConfigError, match="empty"):
        read_login(True)


def test_serve_has_no_password_option_and_refuses_a_login_over_zmq(
    fake: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit):
        main(["serve", "-c", str(fake), "--password", "x"])
    capsys.readouterr()
    code, err = _run(["serve", "-c", str(fake), "--transport", "zmq", "--login"], capsys)
    assert code == 1 and "qimessaging only" in err
