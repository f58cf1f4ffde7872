"""--live: a Foxglove WebSocket client sees naoloc's channels advertised and gets messages.

The client speaks the Foxglove WebSocket protocol itself (``websockets``): JSON
``serverInfo`` and ``advertise`` first, then ``subscribe`` by channel id, then binary
message frames (opcode 1, uint32 subscription id, uint64 log time, payload).
"""

from __future__ import annotations

import asyncio
import json
import re
import select
import signal
import struct
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import websockets
import yaml

import naoloc
from naoloc.viz.live import NO_LIVE, TOPICS, FoxgloveLive, LiveError, open_live, watch

pytestmark = pytest.mark.net

SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]  # foxglove-sdk 0.30 speaks the first
FAKE = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [4.0, 4.0], "seed": 3}}}


async def _watch(port: int, topics: set[str], act: Callable[[], Any]) -> dict[str, bytes]:
    """Connect, wait until ``topics`` are advertised, subscribe, run ``act``, collect one each."""
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=SUBPROTOCOLS) as ws:
        assert ws.subprotocol in SUBPROTOCOLS
        channels: dict[int, tuple[str, str]] = {}
        while not topics <= {t for t, _ in channels.values()}:
            message = json.loads(await asyncio.wait_for(ws.recv(), 10))
            if message["op"] == "advertise":
                for c in message["channels"]:
                    channels[c["id"]] = (c["topic"], c["schemaName"])
        wanted = [cid for cid, (topic, _) in channels.items() if topic in topics]
        subscribe = [{"id": i, "channelId": cid} for i, cid in enumerate(wanted)]
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": subscribe}))
        await asyncio.sleep(0.2)  # the server applies the subscription
        task = asyncio.create_task(asyncio.to_thread(act))
        got: dict[str, bytes] = {}
        deadline = time.monotonic() + 20
        while set(got) != topics and time.monotonic() < deadline:
            frame = await asyncio.wait_for(ws.recv(), 20)
            if isinstance(frame, bytes) and frame[0] == 1:
                sub = struct.unpack_from("<I", frame, 1)[0]
                got.setdefault(channels[wanted[sub]][0], frame[13:])
        await task
        got["_schemas"] = json.dumps({t: s for t, s in channels.values()}).encode()
        return got


def test_every_topic_is_advertised_and_carries_a_message() -> None:
    with FoxgloveLive(0) as live:
        assert isinstance(live, FoxgloveLive)

        def act() -> None:
            live.camera(np.full((24, 32, 3), 128, np.uint8))
            live.odometry((1.0, 2.0, 0.3))
            live.estimate((1.0, 2.0, 3.0), covariance=np.eye(3) * 0.01)
            live.map(np.zeros((5, 3)), np.array([[1.0, 2.0, 1.5], [np.nan, 0, 0]]))
            live.path([(1.0, 1.0), (0.5, 0.5)])

        got = asyncio.run(_watch(live.port, set(TOPICS), act))
    schemas = json.loads(got.pop("_schemas"))
    assert set(got) == set(TOPICS)
    assert schemas["/camera/image"] == "foxglove.CompressedImage"
    assert schemas["/pose/odometry"] == "foxglove.PoseInFrame"
    assert schemas["/pose/estimate/odometry"] == "foxglove.Odometry"
    assert schemas["/map/landmarks"] == "foxglove.PointCloud"
    assert schemas["/go_home/path"] == "foxglove.SceneUpdate"
    assert _jpeg(got["/camera/image"]).shape == (24, 32, 3)
    cloud = got["/map/landmarks"]
    assert np.float32([1.0, 2.0, 1.5]).tobytes() in cloud  # the landmark travelled...
    assert np.float32([np.nan]).tobytes() not in cloud  # ...and the NaN one was left out
    assert b"map" in got["/pose/estimate"] and b"base_link" in got["/pose/estimate/odometry"]


def _jpeg(payload: bytes) -> np.ndarray:
    """The JPEG inside a CompressedImage message (protobuf bytes), decoded."""
    import cv2

    start, end = payload.index(b"\xff\xd8"), payload.rindex(b"\xff\xd9") + 2
    image = cv2.imdecode(np.frombuffer(payload[start:end], np.uint8), cv2.IMREAD_COLOR)
    assert image is not None
    return np.asarray(image)


def test_no_live_is_the_robot_itself_and_a_bad_port_is_one_line() -> None:
    assert open_live(None) is NO_LIVE
    with naoloc.connect(FAKE) as robot:
        assert watch(robot, NO_LIVE) is robot
    with FoxgloveLive(0) as taken, pytest.raises(LiveError, match="cannot listen"):
        FoxgloveLive(taken.port)
    with pytest.raises(LiveError, match="not in 0-65535"):
        open_live(70000)


def _line(stream: Any, pattern: str, process: subprocess.Popen[str], timeout_s: float) -> str:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        ready, _, _ = select.select([stream], [], [], 0.1)
        if ready:
            line = stream.readline()
            match = re.search(pattern, line)
            if match:
                return match.group(1)
        elif process.poll() is not None:
            break
    raise AssertionError(f"no line matching {pattern!r}")


def test_serve_live_streams_what_a_client_asks_the_robot(tmp_path: Path) -> None:
    cfg = tmp_path / "serve.yaml"
    cfg.write_text(yaml.safe_dump(FAKE))
    cmd = [sys.executable, "-m", "naoloc.app.cli", "serve", "-c", str(cfg)]
    cmd += ["--listen", "tcp://127.0.0.1:0", "--transport", "zmq", "--live", "0"]
    process = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert process.stdout is not None and process.stderr is not None
        port = int(_line(process.stderr, r"live view on ws://127\.0\.0\.1:(\d+)", process, 60))
        url = _line(process.stdout, r"listening on (\S+) \(zmq\)", process, 60)
        client = {"robot": {"backend": "naoqi", "url": url, "transport": "zmq"}}

        def act() -> None:
            with naoloc.connect(client) as robot:
                handle = robot.video.subscribeCamera("live-test", 0, 1, 11, 30)
                for _ in range(3):
                    robot.video.getImageRemote(handle)
                    robot.motion.getRobotPosition(True)
                robot.video.unsubscribe(handle)

        got = asyncio.run(_watch(port, {"/camera/image", "/pose/odometry"}, act))
        schemas = json.loads(got.pop("_schemas"))
        assert {"/camera/image", "/pose/odometry"} <= set(schemas)
        assert _jpeg(got["/camera/image"]).shape == (240, 320, 3)  # kQVGA from the fake robot
        assert b"odom" in got["/pose/odometry"]
    finally:
        process.send_signal(signal.SIGTERM)
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def test_the_map_is_latched_for_a_viewer_that_joins_late() -> None:
    from naoloc.viz.live import LATCH_S

    with FoxgloveLive(0) as live:
        live.map(np.zeros((5, 3)), np.array([[1.0, 2.0, 1.5]]))
        time.sleep(LATCH_S + 0.5)  # the viewer connects after the map was sent
        got = asyncio.run(_watch(live.port, {"/map/keyframes", "/map/landmarks"}, lambda: None))
    assert b"map" in got["/map/keyframes"] and b"map" in got["/map/landmarks"]


def test_tf_carries_rep105_frames() -> None:
    with FoxgloveLive(0) as live:

        def act() -> None:
            for _ in range(3):
                live.odometry((1.0, 0.0, 0.0))
                live.estimate((2.0, 1.0, 0.5))
                time.sleep(0.05)

        got = asyncio.run(_watch(live.port, {"/tf"}, act))
    assert b"odom" in got["/tf"] and b"base_link" in got["/tf"]
