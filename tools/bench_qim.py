"""Benchmark naoloc's own QiMessaging against libqi: frame latency and survey time.

Prints, in one run:

1. ``getImageRemote`` QVGA and VGA median latency over loopback from a server that
   returns a cached frame (the transport's own cost), for every client/server pair of
   libqi (the ``qi`` package) and qimessaging (naoloc's pure-Python protocol).
   Targets: qimessaging client against a libqi server, QVGA median <= 2 ms and
   <= 1.3x libqi's own client in the same run.
2. A whole survey through ``naoloc serve --transport qimessaging`` against the same
   survey in-process (target <= 1.3x), and with a qimessaging client against
   ``naoloc serve --transport libqi``.

Usage: ``python tools/bench_qim.py [--backend fake|mujoco] [-n FRAMES] [--repeats R]``.
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
BENCH_NET = Path(__file__).with_name("bench_net.py")


def _latency_ms(robot: Robot, resolution: int, n: int) -> float:
    handle = robot.video.subscribeCamera("bench", 0, resolution, 11, 30)
    try:
        for _ in range(3):
            robot.video.getImageRemote(handle)  # warm up
        times = []
        for _ in range(n):
            t0 = time.perf_counter()
            frame = robot.video.getImageRemote(handle)
            times.append((time.perf_counter() - t0) * 1e3)
            if len(frame[6]) != frame[0] * frame[1] * frame[2]:
                raise SystemExit("bench_qim: a frame of the wrong size")
        return statistics.median(times)
    finally:
        robot.video.unsubscribe(handle)


def _cached_server(transport: str, backend_cfg: dict[str, Any]) -> subprocess.Popen[str]:
    cmd = [sys.executable, str(BENCH_NET), "--serve-cached", transport, "--config-json"]
    cmd.append(json.dumps(backend_cfg))
    return subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)


def _cached_rows(
    server_transport: str, clients: list[str], backend_cfg: dict[str, Any], n: int
) -> dict[str, dict[str, float]]:
    child = _cached_server(server_transport, backend_cfg)
    rows: dict[str, dict[str, float]] = {}
    try:
        assert child.stdout is not None
        url = child.stdout.readline().split("listening on ")[1].split()[0]
        for client_transport in clients:
            cfg = {"robot": {"backend": "naoqi", "url": url, "transport": client_transport}}
            with naoloc.connect(cfg) as robot:
                row = {res: _latency_ms(robot, rid, n) for res, rid in RESOLUTIONS.items()}
            name = f"{client_transport} client -> {server_transport} server"
            print(f"  {name:<40} " + "  ".join(f"{r} {ms:6.2f} ms" for r, ms in row.items()))
            rows[name] = row
    finally:
        if child.stdin is not None:
            child.stdin.close()
        child.wait(timeout=10)
    return rows


def _survey_s(config: dict[str, Any], out: Path) -> float:
    path = out.with_suffix(".yaml")
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    cmd = [sys.executable, "-m", "naoloc.app.cli", "survey", "-c", str(path), "-o", str(out)]
    result = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        raise SystemExit(f"bench_qim: survey failed: {result.stderr.strip()[-300:]}")
    return float(json.loads(result.stdout.strip().splitlines()[-1])["wall_s"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--backend", choices=("fake", "mujoco"), default="fake")
    parser.add_argument("-n", type=int, default=100, help="frames per measurement")
    parser.add_argument("--repeats", type=int, default=3, help="survey runs (best is kept)")
    args = parser.parse_args()
    room = {"size_m": [4.0, 4.0], "seed": 3}
    server_cfg: dict[str, Any] = {"robot": {"backend": args.backend}, "world": {"room": room}}
    libqi = qi_available()
    clients = ["libqi", "qimessaging"] if libqi else ["qimessaging"]
    print(f"bench_qim: getImageRemote median latency, cached frame, n={args.n}")
    rows: dict[str, dict[str, float]] = {}
    for server_transport in ["libqi", "qimessaging"] if libqi else ["qimessaging"]:
        rows.update(_cached_rows(server_transport, clients, server_cfg, args.n))
    if libqi:
        ours = rows["qimessaging client -> libqi server"]["QVGA"]
        theirs = rows["libqi client -> libqi server"]["QVGA"]
        verdict = "met" if ours <= 2.0 and ours <= 1.3 * theirs else "NOT met"
        print(
            f"  QVGA qimessaging/libqi client ratio {ours / theirs:.2f}x, {ours:.2f} ms "
            f"(target <= 2 ms and <= 1.3x): {verdict}"
        )

    survey_cfg: dict[str, Any] = {
        "robot": {"backend": args.backend},
        "world": {"room": {"size_m": [6.0, 6.0], "seed": 3}},
        "survey": {"laps": 2, "step_m": 0.2},
    }
    print(f"survey wall time (160 frames, best of {args.repeats}; target <= 1.3x in-process):")
    pairs = [("qimessaging", "qimessaging")] + ([("libqi", "qimessaging")] if libqi else [])
    with tempfile.TemporaryDirectory() as tmp:
        base = min(_survey_s(survey_cfg, Path(tmp) / "local.mcap") for _ in range(args.repeats))
        print(f"  {'in-process':<40} {base:7.2f} s")
        for server_transport, client_transport in pairs:
            walls = []
            for _ in range(args.repeats):
                with served(survey_cfg, server_transport) as server:
                    client = dict(survey_cfg)
                    client["robot"] = server.client_config(sim_service=True)["robot"]
                    client["robot"]["transport"] = client_transport
                    walls.append(_survey_s(client, Path(tmp) / "net.mcap"))
            wall = min(walls)
            name = f"{client_transport} client -> {server_transport} server"
            print(f"  {name:<40} {wall:7.2f} s  ({wall / base:.2f}x)")


if __name__ == "__main__":
    main()
