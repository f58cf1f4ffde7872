"""Listen and connect URLs: one parser, one-line errors, no silent port wrap-around."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from naoloc.backends.naoqi.urls import parse_url
from naoloc.errors import BackendError


@pytest.mark.parametrize(
    ("text", "scheme", "host", "port"),
    [
        ("tcp://127.0.0.1:9559", "tcp", "127.0.0.1", 9559),
        ("tcp://127.0.0.1:0", "tcp", "127.0.0.1", 0),
        ("tcps://nao.local:9503", "tcps", "nao.local", 9503),
        ("tcp://[::1]:65535", "tcp", "::1", 65535),
        ("tcp://localhost:1", "tcp", "localhost", 1),
    ],
)
def test_good_urls_parse(text: str, scheme: str, host: str, port: int) -> None:
    url = parse_url(text)
    assert (url.scheme, url.host, url.port) == (scheme, host, port)
    assert parse_url(str(url)) == url


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("tcp://[::1", "IPv6"),
        ("tcp://127.0.0.1:99999", "port"),
        ("tcp://127.0.0.1:-1", "port"),
        ("tcp://127.0.0.1:http", "port"),
        ("tcp://127.0.0.1", "port"),
        ("tcp://:9559", "host"),
        ("udp://127.0.0.1:9559", "scheme"),
        ("ipc:///tmp/x", "scheme"),
        ("127.0.0.1:9559", "scheme"),
        ("tcp://127.0.0.1:9559/path", "path"),
        ("tcp://127.0.0.1:9559?x=1", "path"),
        ("tcp://127.0.0.1:95\n59", "control"),
        ("tcp://" + "a" * 5000 + ":1", "long"),
        ("", "empty"),
    ],
)
def test_bad_urls_are_one_line_errors(text: str, fragment: str) -> None:
    with pytest.raises(BackendError) as info:
        parse_url(text, what="--listen")
    message = str(info.value)
    assert "\n" not in message and len(message) < 200
    assert fragment in message and "--listen" in message


def test_port_zero_is_refused_for_a_client() -> None:
    with pytest.raises(BackendError, match="port"):
        parse_url("tcp://127.0.0.1:0", allow_any_port=False)


@pytest.mark.parametrize("listen", ["tcp://[::1", "tcp://127.0.0.1:99999"])
def test_serve_refuses_bad_listen_urls_with_one_line(tmp_path: Path, listen: str) -> None:
    cfg = tmp_path / "c.yaml"
    cfg.write_text("robot: {backend: fake}\nworld: {room: {size_m: [4.0, 4.0]}}\n")
    done = subprocess.run(
        [sys.executable, "-m", "naoloc.app.cli", "serve", "-c", str(cfg), "--transport", "zmq",
         "--listen", listen],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert done.returncode == 1, done.stdout
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "--listen" in lines[0], done.stderr
    assert "listening" not in done.stdout


def test_a_client_url_without_a_port_takes_the_default() -> None:
    assert parse_url("tcp://nao.local", default_port=9559).port == 9559


@pytest.mark.parametrize("url", ["tcp://[::1", "tcp://127.0.0.1:99999", "http://127.0.0.1:1"])
def test_the_client_refuses_bad_robot_urls_with_one_line(url: str) -> None:
    import naoloc

    cfg = {"robot": {"backend": "naoqi", "transport": "zmq", "url": url}}
    with pytest.raises(BackendError, match="robot.url") as info:
        naoloc.connect(cfg)
    assert "\n" not in str(info.value)
