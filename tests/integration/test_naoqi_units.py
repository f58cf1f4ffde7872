"""Units of the naoqi backend: futures, signals, errors, signatures, dead-man, listen policy."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

import naoloc
from naoloc.app.cli import main
from naoloc.app.commands.serve import check_listen, is_loopback
from naoloc.backends.naoqi import session as shim
from naoloc.backends.naoqi.server import ServedRobot, ServiceEndpoint, WatchdogEndpoint
from naoloc.backends.naoqi.signatures import MOTION, SERVICES, select_overload
from naoloc.errors import (
    BackendError,
    ConnectionLost,
    DependencyNotInstalled,
    HandleError,
    RobotError,
)
from naoloc.robot import Robot


def test_future_value_error_and_callbacks() -> None:
    promise = shim.Promise()
    future = promise.future()
    seen: list[str] = []
    future.addCallback(lambda f: seen.append(f.state()))
    assert future.wait(10) == "Running" and not future.isFinished()
    with pytest.raises(ConnectionLost, match="no answer within 10 ms"):
        future.value(10)
    threading.Timer(0.02, promise.setValue, args=([1.0, 2.0],)).start()
    assert future.value(2000) == [1.0, 2.0]
    assert seen == ["FinishedWithValue"] and future.hasValue() and not future.hasError()
    assert promise.setValue(3) is False  # completes once

    failed = shim.Promise()
    failed.setError(HandleError("no handle 'x'"))
    assert failed.future().hasError()
    assert failed.future().error() == "HandleError: no handle 'x'"
    with pytest.raises(HandleError):
        failed.future().value()


def test_signal_connect_emit_disconnect() -> None:
    signal = shim.Signal()
    got: list[str] = []
    link = signal.connect(got.append)
    signal("lost")
    assert signal.disconnect(link) and not signal.disconnect(link)
    signal("again")
    assert got == ["lost"]


@pytest.mark.parametrize(
    ("text", "kind", "message"),
    [
        ("HandleError: no handle 'x'", HandleError, "no handle 'x'"),
        (
            "RuntimeError: MotionError: fell\n\nAt:\n  file.py(3): f",
            naoloc.errors.MotionError,
            "fell",
        ),
        (
            "ALMotion::moveTo: robot is not awake",
            RobotError,
            "ALMotion::moveTo: robot is not awake",
        ),
        ("Socket is not connected", ConnectionLost, "Socket is not connected"),
        ("", RobotError, "remote call failed"),
    ],
)
def test_error_from_text_maps_remote_errors(text: str, kind: type, message: str) -> None:
    err = shim.error_from_text(text)
    assert type(err) is kind and str(err) == message


def test_resolve_transport(monkeypatch: pytest.MonkeyPatch) -> None:
    assert shim.resolve_transport("zmq") == "zmq"
    monkeypatch.setattr(shim, "qi_available", lambda: False)
    assert shim.resolve_transport("auto") == "qimessaging"  # no qi: naoloc's own QiMessaging
    with pytest.raises(DependencyNotInstalled, match=r"pip install 'naoloc\[naoqi\]'"):
        shim.resolve_transport("libqi")
    monkeypatch.setattr(shim, "qi_available", lambda: True)
    assert shim.resolve_transport("auto") == "libqi"
    with pytest.raises(BackendError, match="unknown transport"):
        shim.resolve_transport("grpc")


def test_select_overload_checks_and_converts() -> None:
    assert select_overload(MOTION, "moveTo", [1, 0.5, 0]) == [1.0, 0.5, 0.0]
    assert select_overload(MOTION, "moveTo", [[[0.2, 0, 0]]]) == [[[0.2, 0, 0]]]
    assert select_overload(MOTION, "getRobotPosition", [1]) == [True]
    with pytest.raises(RobotError, match="do not match"):
        select_overload(MOTION, "moveTo", ["a", 0, 0])
    with pytest.raises(RobotError, match="do not match"):
        select_overload(MOTION, "move", [True, 0.0, 0.0])
    with pytest.raises(RobotError, match="do not match"):
        select_overload("ALVideoDevice", "subscribeCamera", ["n", 0, 1, 2**40, 30])
    with pytest.raises(RobotError, match="no method"):
        select_overload(MOTION, "__init__", [])
    with pytest.raises(RobotError, match="unknown service"):
        select_overload("NoSuchService", "say", ["hi"])
    assert select_overload("ALTextToSpeech", "say", ["hi"]) == ["hi"]


def test_every_signature_names_a_method_the_server_implements(
    fake_robot: Robot, tmp_path: Path
) -> None:
    from naoloc.backends.naoqi.signatures import MODULE_METHODS, SIM, WATCHDOG
    from naoloc.config import load_config

    cfg = load_config({"robot": {"backend": "fake"}})  # a config serves NaolocLocalization
    core = ServedRobot(fake_robot, log=lambda _: None, cfg=cfg, record_dir=tmp_path)
    try:
        for service, methods in SERVICES.items():
            if service in (SIM, WATCHDOG):
                target: object = fake_robot.sim
            else:
                target = core.fronts[service]
            for method in methods:
                if method in MODULE_METHODS or (service, method) == ("ALMemory", "subscriber"):
                    continue
                if service != WATCHDOG:
                    assert callable(getattr(target, method, None)), (service, method)
    finally:
        core.stop()


@pytest.fixture
def fake_robot() -> Iterator[Robot]:
    with naoloc.connect({"robot": {"backend": "fake"}}) as robot:
        robot.motion.wakeUp()
        yield robot


def test_deadman_stops_the_motion_of_a_silent_client(fake_robot: Robot) -> None:
    core = ServedRobot(fake_robot, deadman_s=0.2, log=lambda _: None)
    try:
        _silent_client_is_stopped(core)
    finally:
        core.stop()


def _silent_client_is_stopped(core: ServedRobot) -> None:
    motion = ServiceEndpoint(core, "ALMotion")
    watchdog = WatchdogEndpoint(core, "NaolocWatchdog")
    core.touch("driver", heartbeat=True)
    motion.invoke("driver", "move", [0.1, 0, 0])
    assert motion.invoke("observer", "moveIsActive", []) is True
    assert core.check_deadman() is False  # the driver spoke just now
    deadline = time.monotonic() + 0.35
    while time.monotonic() < deadline:  # another client's activity does not keep it alive
        watchdog.invoke("observer", "ping", [])
        time.sleep(0.02)
    assert core.check_deadman() is True
    assert core.deadman_stops == 1
    assert motion.invoke("observer", "moveIsActive", []) is False


def test_deadman_spares_a_client_that_keeps_pinging(fake_robot: Robot) -> None:
    core = ServedRobot(fake_robot, deadman_s=0.2, log=lambda _: None)
    try:
        _pinging_client_is_spared(core)
    finally:
        core.stop()


def _pinging_client_is_spared(core: ServedRobot) -> None:
    motion = ServiceEndpoint(core, "ALMotion")
    motion.invoke("driver", "move", [0.1, 0, 0])
    for _ in range(15):
        WatchdogEndpoint(core, "NaolocWatchdog").invoke("driver", "ping", [])
        time.sleep(0.02)
        assert core.check_deadman() is False
    motion.invoke("driver", "move", [0, 0, 0])  # a zero velocity ends the lasting motion
    time.sleep(0.25)
    assert core.check_deadman() is False


def test_loopback_policy() -> None:
    assert is_loopback("tcp://127.0.0.1:9559") and is_loopback("tcp://localhost:1")
    assert is_loopback("tcp://[::1]:9559") and not is_loopback("tcp://0.0.0.0:9559")
    check_listen("tcp://127.0.0.1:0", "zmq", False, None)
    with pytest.raises(BackendError, match="--allow-remote"):
        check_listen("tcp://0.0.0.0:9559", "libqi", False, None)
    with pytest.raises(BackendError, match="CURVE"):
        check_listen("tcp://0.0.0.0:9559", "zmq", True, None)
    check_listen("tcp://0.0.0.0:9559", "zmq", True, "/keys")
    with pytest.raises(BackendError, match="libqi off loopback"):  # no login: refused
        check_listen("tcp://0.0.0.0:9559", "libqi", True, None)
    with pytest.raises(BackendError, match="tcp://HOST:PORT"):
        check_listen("ipc:///tmp/x", "zmq", False, None)


def test_serve_refuses_a_public_address_without_the_flag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = tmp_path / "c.yaml"
    cfg.write_text("robot: {backend: fake}\n")
    code = main(["serve", "-c", str(cfg), "--listen", "tcp://0.0.0.0:0", "--transport", "zmq"])
    err = capsys.readouterr().err.strip()
    assert code == 1 and len(err.splitlines()) == 1 and "--allow-remote" in err


def test_serve_refuses_a_naoqi_robot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cfg = tmp_path / "c.yaml"
    cfg.write_text("robot: {backend: naoqi}\n")
    assert main(["serve", "-c", str(cfg), "--transport", "zmq"]) == 1
    assert "fake or mujoco" in capsys.readouterr().err
