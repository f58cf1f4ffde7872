"""The served NAOqi under attack and load, per transport: does a stop still get through?

For each transport (qimessaging, zmq, and libqi when the ``qi`` package is installed) a
``naoloc serve`` (fake robot, loopback) takes, one after another:

- fuzz: seeded random QiMessaging frames (zmq: wire requests), ``--messages`` of them;
- flood: clients with 20 blocking calls each in flight (``wbGoToBalance``);
- slow reader: a client asks for 200 kVGA images and never reads them;
- idle: 64 connections that never log in;
- call flood: a client sends calls without reading a reply (``--flood`` calls), on
  and on while the victim runs;
- leftovers: a client takes 64 camera subscriptions and leaves; another subscribes;
  a client fills ALMemory with 512 KiB values and leaves;
- pre-auth bombs (QiMessaging): a 4 KB and a 16 KB nested capability map, the server's
  CPU and memory per message;
- frozen client: a client (the real ``qi`` where installed) starts a velocity walk and
  is stopped with SIGSTOP: how long until the robot stops;
- SIGTERM with the flood running: how long until the server exits.

Under each attack a victim (a fresh client in its own process: the real ``qi`` for the
QiMessaging servers) connects and calls ``ALMotion.stopMove``; its connect and stop
times are printed. At the end: deaths (server exits), tracebacks on its stderr, hangs
(a victim that did not finish in 15 s), thread peak, and RSS growth from the start to
after every attacker left. A qimessaging server with ``--login`` then takes a wrong
password: how long the refusal takes, and whether the robot moved.

Run: ``PYTHONPATH=. .venv/bin/python tools/bench_attack.py`` (about 4 min);
``--short`` is the CI version (1,000 fuzz messages, a shorter flood, no SIGTERM case).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import math
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from naoloc.backends.naoqi.testing import ServedProcess, served  # noqa: E402
from tests.fuzz import attacks  # noqa: E402
from tests.fuzz.libqi_fuzzer import fuzz_libqi  # noqa: E402
from tests.fuzz.zmq_fuzzer import fuzz_zmq  # noqa: E402

PASSWORD = "s3cret-bench"


class Watch:
    """Samples the server's threads while it runs (peak)."""

    def __init__(self, pid: int) -> None:
        self.pid, self.peak = pid, attacks.threads(pid)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(0.05):
            with contextlib.suppress(OSError):
                self.peak = max(self.peak, attacks.threads(self.pid))

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()


@contextlib.contextmanager
def background(send: Callable[[threading.Event], None]) -> Iterator[None]:
    """Run ``send(stop)`` on a thread while the body runs."""
    stop = threading.Event()
    thread = threading.Thread(target=send, args=(stop,), daemon=True)
    thread.start()
    try:
        time.sleep(0.5)
        yield
    finally:
        stop.set()
        thread.join(10)


def flood_on(server: ServedProcess, calls: int) -> Any:
    """A call flood that keeps going while the victim runs."""

    def send(stop: threading.Event) -> None:
        while not stop.is_set():
            with attacks.call_flood(server, calls):
                pass

    return background(send)


def fuzz(server: ServedProcess, messages: int) -> int:
    if server.transport == "zmq":
        return fuzz_zmq(server.url, messages, 11).sent
    return fuzz_libqi(server.url, messages, 11).sent


def leftovers(server: ServedProcess) -> str:
    """64 camera subscriptions and 512 KiB ALMemory values left by clients that leave."""
    import naoloc.qi as nqi

    transport = "zmq" if server.transport == "zmq" else "qimessaging"
    first = nqi.Session(transport=transport)
    first.connect(server.url)
    video = first.service("ALVideoDevice")
    for k in range(64):
        with contextlib.suppress(RuntimeError):
            video.subscribeCamera(f"left{k}", 0, 0, 11, 5)
    first.close()
    second = nqi.Session(transport=transport)
    second.connect(server.url)
    started = time.monotonic()
    got = ""
    while time.monotonic() - started < 10 and not got:
        try:
            got = second.service("ALVideoDevice").subscribeCamera("after", 0, 0, 11, 5)
        except RuntimeError:
            time.sleep(0.1)
    camera = f"camera {'free after %.2f s' % (time.monotonic() - started) if got else 'FULL'}"
    memory = second.service("ALMemory")
    kept = refused = 0
    for k in range(300):
        try:
            memory.insertData(f"bench/{k}", "x" * (512 * 1024))
            kept += 1
        except RuntimeError:
            refused += 1
    second.close()
    return f"{camera}; ALMemory kept {kept} x 512 KiB, refused {refused}"


def warm_up(server: ServedProcess) -> None:
    """A legitimate client takes a kVGA picture: the camera's one-time buffers exist before
    the RSS baseline, so the growth counts what attackers leave, not the first picture."""
    import naoloc.qi as nqi

    session = nqi.Session(transport="zmq" if server.transport == "zmq" else "qimessaging")
    session.connect(server.url)
    video = session.service("ALVideoDevice")
    handle = video.subscribeCamera("warm", 0, 2, 11, 30)
    video.getImageRemote(handle)
    video.unsubscribe(handle)
    session.close()
    victim(server)


def victim(server: ServedProcess, login: tuple[str, str] | None = None) -> tuple[float, float]:
    return attacks.victim_stop(server.url, server.transport, login=login)


def fmt(value: float) -> str:
    return "HANG" if math.isinf(value) else f"{value * 1000:7.1f} ms"


def run_transport(transport: str, messages: int, flood: int, sigterm: bool) -> dict[str, Any]:
    row: dict[str, Any] = {"transport": transport, "hangs": 0}
    worst_stop = 0.0
    with served(attacks.FAKE, transport) as server:
        pid = server.process.pid
        warm_up(server)
        rss0 = attacks.rss_mb(pid)
        watch = Watch(pid)
        started = time.monotonic()
        sent = fuzz(server, messages)
        print(f"  fuzz: {sent} messages in {time.monotonic() - started:.1f} s")
        cases: list[tuple[str, Callable[[], Any]]] = [
            ("fuzzed (after)", contextlib.nullcontext),
            ("20 blocking calls x 4 clients", lambda: attacks.worker_flood(server, 20, 4)),
            ("slow reader (200 kVGA unread)", lambda: attacks.slow_reader(server)),
            ("64 idle connections", lambda: attacks.idle_connections(server, 64)),
            (f"call flood ({flood} unread, ongoing)", lambda: flood_on(server, flood)),
        ]
        for name, attack in cases:
            with attack():
                connect_s, stop_s = victim(server)
            row["hangs"] += math.isinf(connect_s)
            worst_stop = max(worst_stop, stop_s)
            rss = attacks.rss_mb(pid) - rss0
            print(
                f"  {name:34s} victim connect {fmt(connect_s)}  stopMove {fmt(stop_s)}  "
                f"RSS {rss:+6.1f} MB"
            )
        print(f"  leftovers: {leftovers(server)}  RSS {attacks.rss_mb(pid) - rss0:+6.1f} MB")
        if transport != "zmq":
            for size in (4096, 16 * 1024):
                cpu, mem = attacks.preauth_cost(server, size)
                print(f"  pre-auth {size // 1024:2d} KB nested map: {cpu * 1000:6.1f} ms CPU, "
                      f"{mem:+6.1f} MB per message")  # fmt: skip
        frozen = attacks.frozen_client_stop_s(server)
        print(f"  frozen client (SIGSTOP mid-walk): robot stopped after {fmt(frozen)}")
        time.sleep(1.0)
        watch.stop()
        row["growth_mb"] = attacks.rss_mb(pid) - rss0
        row["threads"] = (attacks.threads(pid), watch.peak)
        row["alive"] = server.process.poll() is None
        if sigterm:
            with attacks.worker_flood(server, 20, 4):
                term = time.monotonic()
                server.process.send_signal(signal.SIGTERM)
                try:
                    server.process.wait(10)
                    row["sigterm_s"] = time.monotonic() - term
                except Exception:
                    row["sigterm_s"] = float("inf")
        err = server.stderr()
        row["tracebacks"] = err.count("Traceback")
        row["worst_stop"] = worst_stop
        row["frozen"] = frozen
    print(
        f"  => deaths {0 if row['alive'] else 1}, tracebacks {row['tracebacks']}, hangs "
        f"{row['hangs']}, RSS growth {row['growth_mb']:+.1f} MB, threads {row['threads'][0]} "
        f"(peak {row['threads'][1]}), worst stopMove {fmt(worst_stop)}"
        + (f", SIGTERM exit {fmt(row['sigterm_s'])}" if "sigterm_s" in row else "")
    )
    return row


def wrong_password() -> dict[str, Any]:
    """A qimessaging server with --login: a wrong password never moves the robot."""
    env = {"NAOLOC_SERVE_PASSWORD": PASSWORD}
    with served(attacks.FAKE, "qimessaging", args=["--login"], env=env) as server:
        sid, move, params = attacks.method_address(server.url, "ALMotion", "move", PASSWORD)
        raw = attacks.RawQi(server.url, login=("nao", "wrong"))
        started = time.monotonic()
        raw.call(sid, 1, move, attacks.encode_args(params, 0.3, 0.0, 0.0))
        answers = []
        with contextlib.suppress(OSError, ConnectionError, TimeoutError):
            while True:
                answers.append(raw.read(5.0)[0].type)
        refused_s = time.monotonic() - started
        raw.close()
        moved = attacks.moved(server.url, PASSWORD)
        connect_s, stop_s = victim(server, ("nao", PASSWORD))
    print(
        f"  wrong password: answered {answers} then closed after {refused_s:.2f} s; "
        f"robot moved: {moved}; a right login's stopMove {fmt(stop_s)} "
        f"(connect {fmt(connect_s)})"
    )
    return {"refused_s": refused_s, "moved": moved}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--short", action="store_true", help="the CI version")
    parser.add_argument("--transports", default="qimessaging,zmq,libqi")
    args = parser.parse_args()
    messages, flood = (1_000, 2_000) if args.short else (12_000, 20_000)
    transports = [t for t in args.transports.split(",") if t]
    if "libqi" in transports and importlib.util.find_spec("qi") is None:
        transports.remove("libqi")
    os.environ.setdefault("MUJOCO_GL", "egl")
    rows = []
    for transport in transports:
        print(f"{transport}:")
        rows.append(run_transport(transport, messages, flood, sigterm=not args.short))
    if "qimessaging" in transports:
        print("qimessaging --login:")
        wrong_password()
    bad = [r["transport"] for r in rows if r["tracebacks"] or r["hangs"] or not r["alive"]]
    print("FAIL: " + ", ".join(bad) if bad else "no deaths, tracebacks or hangs")


if __name__ == "__main__":
    main()
