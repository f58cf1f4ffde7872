"""Benchmark the NAOqi network backend: frame latency and survey time, in-process vs network.

Prints, in one run:

1. ``getImageRemote`` median latency at QVGA and VGA: in-process, and over loopback
   through `naoloc serve` with libqi and with zmq (end to end, rendering included).
2. The same over a server that returns a cached frame, i.e. the transport's own cost
   (target: a QVGA frame in at most 2 ms median on both transports).
3. A whole survey's wall time in-process and through the network (target: at most 1.3x):
   the paper's room and circuit, 160 frames, best of ``--repeats`` runs each.

The served robot runs on the server's real-time clock (``naoloc serve --speed``): the
latency rows at 1.0 (a NAO's pace), the survey at ``--survey-speed`` (default 100):
at 1.0 the survey's 32 m of walking alone take over 5 minutes, whatever the transport.

Usage: ``python tools/bench_net.py [--backend fake|mujoco] [-n FRAMES] [--survey-speed K]``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import yaml

os.environ.setdefault("MUJOCO_GL", "egl")

import naoloc
from naoloc.backends.naoqi.session import qi_available
from naoloc.backends.naoqi.testing import served
from naoloc.robot import Robot

RESOLUTIONS = {"QVGA": 1, "VGA": 2}


def _latency_ms(robot: Robot, resolution: int, n: int) -> float:
    handle = robot.video.subscribeCamera("bench", 0, resolution, 11, 30)
    try:
        robot.video.getImageRemote(handle)  # warm up
        times = []
        for _ in range(n):
            t0 = time.perf_counter()
            frame = robot.video.getImageRemote(handle)
            times.append((time.perf_counter() - t0) * 1e3)
            if len(frame[6]) != frame[0] * frame[1] * frame[2]:
                raise SystemExit("bench_net: a frame of the wrong size")
        return statistics.median(times)
    finally:
        robot.video.unsubscribe(handle)


def _row(name: str, robot: Robot, n: int) -> dict[str, float]:
    row = {res: _latency_ms(robot, rid, n) for res, rid in RESOLUTIONS.items()}
    print(f"  {name:<28} " + "  ".join(f"{res} {ms:7.2f} ms" for res, ms in row.items()))
    return row


def serve_cached(transport: str, backend_cfg: dict[str, Any]) -> None:
    """Child mode: serve a robot whose camera returns one cached frame per subscription."""
    from naoloc.backends.naoqi.server import RobotThread, VirtualNaoqi

    thread = RobotThread()  # the robot is created, called and closed on one thread
    robot = thread.run(naoloc.connect, backend_cfg)
    real = robot.video.getImageRemote
    cache: dict[str, list[Any]] = {}

    def cached(handle: str) -> list[Any]:
        if handle not in cache:
            cache[handle] = real(handle)
        return cache[handle]

    robot.video.getImageRemote = cached  # type: ignore[method-assign,assignment]
    url, kind = "tcp://127.0.0.1:0", transport
    try:
        with VirtualNaoqi(robot, url, kind, thread=thread) as server:  # type: ignore[arg-type]
            print(f"naoloc serve: listening on {server.endpoint} ({transport})", flush=True)
            sys.stdin.read()  # until the parent closes our stdin
    finally:
        thread.run(robot.close)
        thread.close()


def _cached_row(transport: str, backend_cfg: dict[str, Any], n: int) -> dict[str, float]:
    cmd = [sys.executable, __file__, "--serve-cached", transport, "--config-json"]
    cmd.append(json.dumps(backend_cfg))
    child = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout is not None
        line = child.stdout.readline()
        url = line.split("listening on ")[1].split()[0]
        client = {"robot": {"backend": "naoqi", "url": url, "transport": transport}}
        with naoloc.connect(client) as robot:
            return _row(f"{transport} (cached frame)", robot, n)
    finally:
        if child.stdin is not None:
            child.stdin.close()
        child.wait(timeout=10)


def _survey_s(config: dict[str, Any], out: Path) -> float:
    path = out.with_suffix(".yaml")
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    cmd = [sys.executable, "-m", "naoloc.app.cli", "survey", "-c", str(path), "-o", str(out)]
    result = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        raise SystemExit(f"bench_net: survey failed: {result.stderr.strip()[-300:]}")
    return float(json.loads(result.stdout.strip().splitlines()[-1])["wall_s"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--backend", choices=("fake", "mujoco"), default="fake")
    parser.add_argument("-n", type=int, default=60, help="frames per measurement")
    parser.add_argument("--repeats", type=int, default=3, help="survey runs (best is kept)")
    parser.add_argument(
        "--survey-speed", type=float, default=100.0, help="server clock speed for the survey"
    )
    parser.add_argument("--serve-cached", default=None, help=argparse.SUPPRESS)
    parser.add_argument("--config-json", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.serve_cached:
        serve_cached(args.serve_cached, json.loads(args.config_json))
        return
    room = {"size_m": [4.0, 4.0], "seed": 3}
    server_cfg: dict[str, Any] = {"robot": {"backend": args.backend}, "world": {"room": room}}
    transports = ["libqi", "zmq"] if qi_available() else ["zmq"]
    print(f"bench_net: getImageRemote median latency, {args.backend} robot, n={args.n}")
    with naoloc.connect(server_cfg) as robot:
        robot.motion.wakeUp()
        _row("in-process", robot, args.n)
    for transport in transports:
        with (
            served(server_cfg, transport) as server,
            naoloc.connect(server.client_config()) as robot,
        ):
            _row(f"{transport} (end to end)", robot, args.n)
    print("transport only (the server returns a cached frame; target QVGA <= 2 ms):")
    for transport in transports:
        _cached_row(transport, server_cfg, args.n)

    # A whole survey: the paper's 6 x 6 m room, 2 laps of a 4 x 4 m square in 0.2 m steps
    # (160 frames), the nearest wall found by parallax as always; best of --repeats runs.
    survey_cfg: dict[str, Any] = {
        "robot": {"backend": args.backend},
        "world": {"room": {"size_m": [6.0, 6.0], "seed": 3}},
        "survey": {"laps": 2, "step_m": 0.2},
    }
    print(
        f"survey wall time (2 laps of a 4 x 4 m square, 160 frames, best of {args.repeats}; "
        f"server clock at {args.survey_speed:g} x real time; target network <= 1.3x in-process):"
    )
    with tempfile.TemporaryDirectory() as tmp:
        base = min(_survey_s(survey_cfg, Path(tmp) / "local.mcap") for _ in range(args.repeats))
        print(f"  {'in-process':<28} {base:7.2f} s")
        for transport in transports:
            walls = []
            for _ in range(args.repeats):  # a fresh robot each time, at the start pose
                with served(survey_cfg, transport, speed=args.survey_speed) as server:
                    client = dict(survey_cfg)
                    client["robot"] = server.client_config(sim_service=True)["robot"]
                    walls.append(_survey_s(client, Path(tmp) / f"{transport}.mcap"))
            wall = min(walls)
            print(f"  {transport:<28} {wall:7.2f} s  ({wall / base:.2f}x)")


if __name__ == "__main__":
    main()
