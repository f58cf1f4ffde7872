"""Run ``naoloc serve`` in a subprocess on a free loopback port (tests and benchmarks).

libqi servers live in their own process to stay clear of libqi's process-wide state;
the zmq server is run the same way so both transports are tested alike.
"""

from __future__ import annotations

import contextlib
import os
import re
import select
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import yaml

from naoloc.errors import BackendError

_LISTENING = re.compile(r"listening on (\S+) \((\w+)\)")


@dataclass
class ServedProcess:
    """A running ``naoloc serve``.

    Attributes:
        url: The endpoint clients connect to.
        transport: ``libqi`` or ``zmq``.
        process: The subprocess.
        stderr_path: File collecting its stderr.
    """

    url: str
    transport: str
    process: subprocess.Popen[str]
    stderr_path: Path

    def stderr(self) -> str:
        """What the server wrote to stderr so far."""
        return self.stderr_path.read_text(encoding="utf-8", errors="replace")

    def client_config(self, **robot: Any) -> dict[str, Any]:
        """A naoqi-backend config dict pointing at this server (extra ``robot`` keys merged)."""
        keys = {"backend": "naoqi", "url": self.url, "transport": self.transport}
        keys.update(robot)
        return {"robot": keys}


def _read_endpoint(stdout: IO[str], process: subprocess.Popen[str], timeout_s: float) -> str:
    deadline = time.monotonic() + timeout_s
    lines = []
    while time.monotonic() < deadline:
        ready, _, _ = select.select([stdout], [], [], 0.1)
        if not ready:
            if process.poll() is not None:
                break
            continue
        line = stdout.readline()
        if not line:
            break
        lines.append(line)
        match = _LISTENING.search(line)
        if match:
            return match.group(1)
    raise BackendError(f"naoloc serve did not start: {''.join(lines).strip()[:200]}")


@contextlib.contextmanager
def served(
    config: dict[str, Any],
    transport: str,
    *,
    listen: str = "tcp://127.0.0.1:0",
    start_timeout_s: float = 60.0,
    speed: float | None = None,
    args: Sequence[str] = (),
    env: dict[str, str] | None = None,
) -> Iterator[ServedProcess]:
    """Start ``naoloc serve -c <config> --listen <listen> --transport <transport>``.

    Args:
        config: The server's config (a fake or mujoco robot) as a dict.
        transport: ``libqi`` or ``zmq``.
        listen: Listen URL; port 0 picks a free port.
        start_timeout_s: Longest wait for the "listening on" line.
        speed: ``--speed`` (simulated seconds per wall second); None = the default 1.0.
        args: More command-line arguments (e.g. ``--login``, ``--tls-cert``).
        env: More environment variables (e.g. ``NAOLOC_SERVE_PASSWORD``).

    Yields:
        The running server; on exit it gets SIGTERM (SIGKILL after 5 s).

    Raises:
        BackendError: The server did not start (its first output lines in the message).
    """
    with tempfile.TemporaryDirectory(prefix="naoloc-serve-") as tmp:
        cfg_path = Path(tmp) / "serve.yaml"
        cfg_path.write_text(yaml.safe_dump(config), encoding="utf-8")
        err_path = Path(tmp) / "stderr.txt"
        cmd = [sys.executable, "-m", "naoloc.app.cli", "serve", "-c", str(cfg_path)]
        cmd += ["--listen", listen, "--transport", transport]
        if speed is not None:
            cmd += ["--speed", repr(float(speed))]
        cmd += list(args)
        environ = dict(os.environ)
        environ.setdefault("MUJOCO_GL", "egl")
        environ.update(env or {})
        with err_path.open("w", encoding="utf-8") as err_file:
            process = subprocess.Popen(
                cmd, stdout=subprocess.PIPE, stderr=err_file, text=True, env=environ,
                stdin=subprocess.DEVNULL,
            )  # fmt: skip
            try:
                assert process.stdout is not None
                url = _read_endpoint(process.stdout, process, start_timeout_s)
                yield ServedProcess(url, transport, process, err_path)
            finally:
                stop(process)


def stop(process: subprocess.Popen[str], timeout_s: float = 5.0) -> None:
    """SIGTERM a server, SIGKILL it if it does not exit within ``timeout_s``."""
    if process.poll() is None:
        process.send_signal(signal.SIGTERM)
        try:
            process.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
    if process.stdout is not None:
        process.stdout.close()
