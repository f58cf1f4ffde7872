"""Issue 33, item 3: ROS 2 without ROS.

``--format ros2`` writes MCAP that the mcap library's ROS 2 reader decodes (sensor_msgs
Image and CameraInfo, nav_msgs Odometry, tf2_msgs TFMessage, geometry_msgs
PoseWithCovarianceStamped), and a recording as naoqi_driver2 makes it (its topics, its tf
tree with base_footprint below base_link and an optical camera frame, rgb8 images, odometry
faster than the camera) becomes a survey dataset that builds a map. No ROS install.
"""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from naoloc.app.cli import main
from tests.rooms import PIPELINE_ROOM as ROOM
from tests.rooms import run_json

AT = ["1.4", "2.2", "0.6"]


def _decoded(path: Path | str, topics: list[str] | None = None) -> list[Any]:
    """Every message decoded by the mcap library's ROS 2 decoder: (topic, schema, msg)."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [
            (channel.topic, schema.name, msg)
            for schema, channel, _, msg in reader.iter_decoded_messages(topics=topics)
        ]


@pytest.fixture(scope="module")
def surveyed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    tmp = tmp_path_factory.mktemp("ros2")
    cfg = tmp / "f.yaml"
    cfg.write_text(yaml.safe_dump(ROOM), encoding="utf-8")
    out = tmp / "s.mcap"
    assert main(["survey", "-c", str(cfg), "-o", str(out), "--format", "ros2"]) == 0
    return cfg, out


@pytest.mark.slow
def test_format_ros2_decodes_with_the_mcap_ros2_reader(
    surveyed: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mcap.reader import make_reader

    from naoloc.data.dataset import read_dataset

    cfg, survey = surveyed
    ros2 = survey.with_suffix(".ros2.mcap")
    with open(ros2, "rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert summary is not None
        assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
    kinds: Counter[tuple[str, str]] = Counter()
    frames: set[tuple[str, str]] = set()
    for topic, name, msg in _decoded(ros2):
        kinds[(topic, name)] += 1
        if name == "tf2_msgs/msg/TFMessage":
            frames |= {(t.header.frame_id, t.child_frame_id) for t in msg.transforms}
        elif name == "sensor_msgs/msg/Image":
            assert (msg.width, msg.height, msg.encoding) == (320, 240, "bgr8")
            assert len(msg.data) == 320 * 240 * 3
        elif name == "sensor_msgs/msg/CameraInfo":
            assert msg.distortion_model == "plumb_bob" and len(msg.k) == 9
        elif name == "nav_msgs/msg/Odometry":
            assert (msg.header.frame_id, msg.child_frame_id) == ("odom", "base_footprint")
    n = len(read_dataset(survey).keyframes) + len(read_dataset(survey).far)
    for topic, kind in [
        ("/camera/front/image_raw", "sensor_msgs/msg/Image"),
        ("/camera/front/camera_info", "sensor_msgs/msg/CameraInfo"),
        ("/odom", "nav_msgs/msg/Odometry"),
        ("/tf", "tf2_msgs/msg/TFMessage"),
        ("/joint_states", "sensor_msgs/msg/JointState"),
    ]:
        assert kinds[(topic, kind)] == n, (topic, kinds)
    assert {("map", "odom"), ("odom", "base_footprint"), ("base_footprint", "CameraTop_frame"),
            ("CameraTop_frame", "CameraTop_optical_frame")} <= frames  # fmt: skip

    # A recording's estimates: PoseWithCovarianceStamped in the map frame.
    vmap = tmp_path / "m.npz"
    assert main(["build-map", "-c", str(cfg), "-d", str(survey), "-o", str(vmap)]) == 0
    capsys.readouterr()
    rec = tmp_path / "r.mcap"
    got = run_json(["localize", "-c", str(cfg), "-m", str(vmap), "--at", *AT, "--record", str(rec),
                "--format", "ros2"], capsys)  # fmt: skip
    estimates = [msg for _, _, msg in _decoded(got["ros2"], topics=["/pose/estimate"])]
    assert estimates and estimates[-1].header.frame_id == "map"
    last = estimates[-1].pose
    assert last.pose.position.x == pytest.approx(got["x"], abs=1e-4)
    assert last.covariance[0] > 0 and last.covariance[35] > 0  # x and yaw variances


@pytest.mark.slow
def test_our_ros2_survey_reads_back_exactly_and_builds_a_map(
    surveyed: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from naoloc.data.dataset import read_dataset

    cfg, survey = surveyed
    ros2 = survey.with_suffix(".ros2.mcap")
    ours, back = read_dataset(survey), read_dataset(ros2)
    by_stamp = {k.stamp: k for k in back.keyframes}
    for kf in ours.keyframes:
        other = by_stamp[kf.stamp]
        assert np.array_equal(kf.image, other.image)
        assert abs(kf.pose.x - other.pose.x) < 1e-9 and abs(kf.pose.y - other.pose.y) < 1e-9
        assert np.allclose(kf.camera_pose, other.camera_pose, atol=1e-12)
        assert (kf.head_yaw, kf.head_pitch) == (other.head_yaw, other.head_pitch)
    vmap = tmp_path / "m.npz"
    built = run_json(["build-map", "-c", str(cfg), "-d", str(ros2), "-o", str(vmap),
                  "--keep-unchecked"], capsys)  # fmt: skip
    assert built["images"] == len(back.keyframes) and built["checked"] is False
    from naoloc.geometry import Pose2D, relative_pose

    found = run_json(["localize", "-c", str(cfg), "-m", str(vmap), "--at", *AT], capsys)
    origin = Pose2D.from_list(ours.meta["origin_room_pose"])  # the same map frame
    truth = relative_pose(origin, Pose2D(*(float(v) for v in AT)))
    assert found["status"] == "tracking"
    assert math.hypot(found["x"] - truth.x, found["y"] - truth.y) < 0.1


def _driver2_bag(survey: Path, out: Path) -> int:
    """A recording as naoqi_driver2 makes it, from a survey's pictures and kinematics."""
    from mcap_ros2.writer import Writer

    from naoloc.data.dataset import calibration, read_dataset
    from naoloc.data.ros2 import _OPTICAL, _planar, _quat, msgdef
    from naoloc.robot.lens import Lens

    data = read_dataset(survey)
    lens = Lens.from_dict(data.meta.get("lens"))
    torso = np.eye(4)
    torso[2, 3] = 0.33  # base_link (the torso) above base_footprint
    neck = np.eye(4)
    neck[2, 3] = 0.1265  # Head above the torso
    with open(out, "wb") as f:
        w = Writer(f)
        schema = {
            n: w.register_msgdef(n.replace("/", "/msg/"), msgdef(n))
            for n in ("sensor_msgs/Image", "sensor_msgs/CameraInfo", "nav_msgs/Odometry",
                      "tf2_msgs/TFMessage", "sensor_msgs/JointState")
        }  # fmt: skip

        def put(topic: str, kind: str, t: float, msg: Any) -> None:
            w.write_message(topic, schema[kind], msg, log_time=round(t * 1e9))

        def header(t: float, frame: str) -> dict[str, Any]:
            ns = round(t * 1e9)
            return {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": frame}

        def tf(t: float, parent: str, child: str, m: np.ndarray) -> dict[str, Any]:
            return {"header": header(t, parent), "child_frame_id": child, "transform": {
                "translation": {"x": m[0, 3], "y": m[1, 3], "z": m[2, 3]},
                "rotation": _quat(m[:3, :3])}}  # fmt: skip

        optical = np.eye(4)
        optical[:3, :3] = _OPTICAL
        put("/tf_static", "tf2_msgs/TFMessage", 0.0, {"transforms": [
            tf(0.0, "CameraTop_frame", "CameraTop_optical_frame", optical)]})  # fmt: skip
        raw = Lens(1.0, 1.0, 0.0, 0.0, 0.0)
        start = data.keyframes[0].pose
        odom0 = np.array([3.0, -2.0, 1.0])  # the driver's odom starts anywhere (robot boot)
        for kf in data.keyframes:
            t = kf.stamp
            c, s = math.cos(odom0[2]), math.sin(odom0[2])
            p = kf.pose
            odo = (odom0[0] + c * p.x - s * p.y, odom0[1] + s * p.x + c * p.y, odom0[2] + p.theta)
            for dt in (-0.03, 0.0, 0.04):  # odometry at ~30 Hz around each picture
                tr, q = _planar(type(start)(*odo))
                put("/naoqi_driver/odom", "nav_msgs/Odometry", t + dt, {
                    "header": header(t + dt, "odom"), "child_frame_id": "base_link",
                    "pose": {"pose": {"position": {**tr, "z": 0.33}, "orientation": q},
                             "covariance": [0.0] * 36},
                    "twist": {"twist": {"linear": {}, "angular": {}}, "covariance": [0.0] * 36},
                })  # fmt: skip
            world = np.eye(4)
            world[:3, :3] = [[math.cos(odo[2]), -math.sin(odo[2]), 0],
                             [math.sin(odo[2]), math.cos(odo[2]), 0], [0, 0, 1]]  # fmt: skip
            world[:2, 3] = odo[:2]
            cam = np.asarray(kf.camera_pose).reshape(4, 4)  # in base_footprint
            head_cam = np.linalg.inv(torso @ neck) @ cam
            put("/tf", "tf2_msgs/TFMessage", t - 0.01, {"transforms": [
                tf(t - 0.01, "odom", "base_link", world @ torso),
                tf(t - 0.01, "base_link", "base_footprint", np.linalg.inv(torso)),
                tf(t - 0.01, "base_link", "Head", neck),
                tf(t - 0.01, "Head", "CameraTop_frame", head_cam)]})  # fmt: skip
            put("/naoqi_driver/joint_states", "sensor_msgs/JointState", t, {
                "header": header(t, ""), "name": ["HeadYaw", "HeadPitch", "LShoulderPitch"],
                "position": [kf.head_yaw, kf.head_pitch, 1.4], "velocity": [], "effort": [],
            })  # fmt: skip
            k, d = calibration(kf.camera, lens or raw)
            rgb = np.ascontiguousarray(kf.image[:, :, ::-1])
            put("/naoqi_driver/camera/front/camera_info", "sensor_msgs/CameraInfo", t, {
                "header": header(t, "CameraTop_optical_frame"), "height": 240, "width": 320,
                "distortion_model": "plumb_bob", "d": d, "k": k,
                "r": [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
                "p": [k[0], 0, k[2], 0, 0, k[4], k[5], 0, 0, 0, 1.0, 0], "binning_x": 0,
                "binning_y": 0, "roi": {}})  # fmt: skip
            put("/naoqi_driver/camera/front/image_raw", "sensor_msgs/Image", t, {
                "header": header(t, "CameraTop_optical_frame"), "height": 240, "width": 320,
                "encoding": "rgb8", "is_bigendian": 0, "step": 960, "data": rgb.tobytes(),
            })  # fmt: skip
        w.finish()
    return len(data.keyframes)


@pytest.mark.slow
def test_a_naoqi_driver2_recording_becomes_a_survey_that_builds_a_map(
    surveyed: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from naoloc.data.dataset import read_dataset

    cfg, survey = surveyed
    bag = tmp_path / "driver2.mcap"
    n = _driver2_bag(survey, bag)
    data, ours = read_dataset(bag), read_dataset(survey)
    assert len(data.keyframes) == n and data.meta["source"] == "ros2"
    first = ours.keyframes[0].pose
    for kf, mine in zip(data.keyframes, ours.keyframes, strict=True):
        assert np.array_equal(kf.image, mine.image)  # rgb8 turned back to BGR
        rel = (first.inverse() * mine.pose).normalized()  # no map frame: the first picture's
        assert abs(kf.pose.x - rel.x) < 1e-9 and abs(kf.pose.y - rel.y) < 1e-9
        assert np.allclose(kf.camera_pose, mine.camera_pose, atol=1e-9)  # base_footprint
        assert kf.head_yaw == mine.head_yaw
    built = run_json(["build-map", "-c", str(cfg), "-d", str(bag), "-o", str(tmp_path / "d.npz"),
                  "--keep-unchecked"], capsys)  # fmt: skip
    assert built["images"] == n and built["neurons"] == 30
