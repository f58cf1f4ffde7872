"""Survey datasets: MCAP round trip, Foxglove schemas and indexes, partial files.

Corrupt and hostile files are in test_dataset_corrupt.py.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from naoloc.data.dataset import (
    FORMAT_VERSION,
    DatasetWriter,
    _protobuf_fields,
    partial_path_for,
    read_dataset,
)
from naoloc.errors import DatasetError
from naoloc.geometry import Pose2D
from naoloc.robot.keyframe import CameraInfo, Keyframe


def _keyframe(i: int, rng: np.random.Generator) -> Keyframe:
    # Smooth random image: survives JPEG well enough to compare.
    small = rng.integers(0, 255, (12, 16, 3), dtype=np.uint8)
    image = np.kron(small, np.ones((20, 20, 1), dtype=np.uint8))
    return Keyframe(
        image=image,
        pose=Pose2D(0.2 * i, 0.01 * i, 0.05 * i),
        head_yaw=-1.57,
        head_pitch=-0.2,
        camera=CameraInfo(320, 240, 1.06, 0.83, 0),
        stamp=1.5 * i,
        command_pose=Pose2D(0.2 * i, 0.0, 0.0),
        true_pose=Pose2D(1.0 + 0.2 * i, 1.0, 0.0),
    )


META = {"room_size_m": [6, 6], "origin_room_pose": [1.0, 2.0, 0.5]}


def _write(path: Path, n: int, finish: bool = True, complete: bool = True) -> list[Keyframe]:
    rng = np.random.default_rng(0)
    frames = [_keyframe(i, rng) for i in range(n)]
    writer = DatasetWriter(path, config={"survey": {"laps": 1}}, meta=META)
    for i, kf in enumerate(frames):
        writer.write(kf, lap=i // 3, odometry=Pose2D(5.0, 5.0, 1.0))
    if finish:
        writer.close(complete=complete, reason="" if complete else "interrupted (SIGINT)")
    else:
        writer._file.flush()  # the process "dies" here: no summary, no footer
    return frames


def test_round_trip_keeps_every_field(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    frames = _write(path, 5)
    data = read_dataset(path)
    assert data.complete
    assert data.config == {"survey": {"laps": 1}}
    assert data.meta == {**META, "complete": True, "frames": 5}
    assert data.laps == [0, 0, 0, 1, 1]
    assert len(data.keyframes) == 5
    for want, got in zip(frames, data.keyframes, strict=True):
        assert got.pose == want.pose
        assert got.command_pose == want.command_pose
        assert got.true_pose == want.true_pose
        assert got.head_yaw == want.head_yaw and got.head_pitch == want.head_pitch
        assert got.camera == want.camera
        assert got.stamp == want.stamp
        assert got.image.shape == want.image.shape
        diff = np.abs(got.image.astype(int) - want.image.astype(int)).mean()
        assert diff < 8.0  # JPEG; a wrong image differs by about 85


def test_png_is_lossless(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    rng = np.random.default_rng(1)
    kf = _keyframe(0, rng)
    with DatasetWriter(path, config={}, meta={}, image_format="png") as w:
        w.write(kf)
    assert np.array_equal(read_dataset(path).keyframes[0].image, kf.image)


def test_foxglove_schemas_are_inside(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    path = tmp_path / "s.mcap"
    _write(path, 2)
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    names = {s.name: s.encoding for s in summary.schemas.values()}
    assert names["foxglove.CompressedImage"] == "protobuf"
    assert names["foxglove.PoseInFrame"] == "protobuf"
    assert names["foxglove.CameraCalibration"] == "protobuf"
    assert names["foxglove.FrameTransform"] == "protobuf"
    topics = {c.topic for c in summary.channels.values()}
    assert {"/camera/image", "/pose/odometry", "/pose/truth", "/tf"} <= topics
    # The schema bytes are Foxglove's own descriptor set, not a placeholder.
    image_schema = next(s for s in summary.schemas.values() if s.name.endswith("CompressedImage"))
    assert b"CompressedImage" in image_schema.data and len(image_schema.data) > 100


def test_writer_that_died_leaves_every_frame(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    _write(path, 4, finish=False)
    assert not path.exists()
    data = read_dataset(tmp_path / "s.partial.mcap")
    assert not data.complete and data.meta["complete"] is False
    assert "died" in data.meta["reason"]
    assert len(data.keyframes) == 4


def test_truncated_tail_keeps_the_whole_frames(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    _write(path, 4, finish=False)
    raw = partial_path_for(path).read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(raw[: len(raw) - 300])  # inside the last frame's chunk
    data = read_dataset(cut)
    assert len(data.keyframes) == 3 and not data.complete
    assert [kf.pose.x for kf in data.keyframes] == pytest.approx([0.0, 0.2, 0.4])


def test_partial_path_keeps_the_mcap_extension() -> None:
    assert partial_path_for(Path("runs/s.mcap")) == Path("runs/s.partial.mcap")
    assert partial_path_for(Path("runs/s")) == Path("runs/s.partial.mcap")


def test_interrupted_writer_keeps_the_complete_dataset_and_a_marked_partial(
    tmp_path: Path,
) -> None:
    path = tmp_path / "s.mcap"
    _write(path, 5)
    before = path.read_bytes()
    _write(path, 3, complete=False)  # e.g. Ctrl-C during a second survey
    assert path.read_bytes() == before  # the complete dataset is untouched
    partial = read_dataset(tmp_path / "s.partial.mcap")
    assert not partial.complete and len(partial.keyframes) == 3
    assert partial.meta["complete"] is False and partial.meta["frames"] == 3
    assert partial.meta["reason"] == "interrupted (SIGINT)"
    assert read_dataset(path).complete


def test_context_manager_exit_by_exception_keeps_a_partial(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    with pytest.raises(RuntimeError), DatasetWriter(path, config={}, meta={}) as w:
        w.write(_keyframe(0, np.random.default_rng(0)))
        raise RuntimeError("robot fell")
    assert not path.exists()
    data = read_dataset(partial_path_for(path))
    assert not data.complete and data.meta["reason"] == "RuntimeError: robot fell"


def test_file_is_chunked_and_indexed_with_room_to_map(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    path = tmp_path / "s.mcap"
    _write(path, 4)
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None
        assert len(summary.chunk_indexes) == 4  # one chunk per frame
        assert all(c.compression == "zstd" for c in summary.chunk_indexes)
        assert all(c.message_index_offsets for c in summary.chunk_indexes)
        # Seeking by time through the indexes reaches the third frame's image directly.
        t2 = round(1.5 * 2 * 1e9)
        msgs = list(reader.iter_messages(topics=["/camera/image"], starting_at=t2))
        assert [m.log_time for _, _, m in msgs] == [t2, round(1.5 * 3 * 1e9)]
        tfs = [_protobuf_fields(m.data) for _, _, m in reader.iter_messages(topics=["/tf"])]
    room = [tf for tf in tfs if tf[2] == [b"room"] and tf[3] == [b"map"]]
    assert len(room) == 4  # with every frame
    translation = _protobuf_fields(room[0][4][0])
    x, y = (np.frombuffer(translation[k][0], "<f8")[0] for k in (1, 2))
    assert (x, y) == (1.0, 2.0)  # the meta's origin_room_pose
    rotation = _protobuf_fields(room[0][5][0])
    qz, qw = (np.frombuffer(rotation[k][0], "<f8")[0] for k in (3, 4))
    assert 2 * math.atan2(qz, qw) == pytest.approx(0.5)
    assert {(tf[2][0], tf[3][0]) for tf in tfs} == {
        (b"room", b"map"), (b"map", b"odom"), (b"odom", b"base_link"), (b"base_link", b"camera")
    }  # REP-105 with the raw odometry given  # fmt: skip


def test_no_room_to_map_without_an_origin(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    path = tmp_path / "s.mcap"
    with DatasetWriter(path, config={}, meta={"origin_room_pose": None}) as w:
        w.write(_keyframe(0, np.random.default_rng(0)))
    with open(path, "rb") as f:
        parents = {
            _protobuf_fields(m.data)[2][0]
            for _, _, m in make_reader(f).iter_messages(topics=["/tf"])
        }
    assert parents == {b"map", b"base_link"}


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "not an MCAP file"),
        (b"hello, this is text" * 5, "not an MCAP file"),
    ],
)
def test_foreign_files_fail_in_one_line(tmp_path: Path, content: bytes, message: str) -> None:
    path = tmp_path / "x.mcap"
    path.write_bytes(content)
    with pytest.raises(DatasetError, match=message) as info:
        read_dataset(path)
    assert "\n" not in str(info.value)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(DatasetError, match="no such dataset"):
        read_dataset(tmp_path / "nope.mcap")


def test_foreign_mcap_is_refused(tmp_path: Path) -> None:
    from mcap.writer import Writer

    path = tmp_path / "other.mcap"
    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema("x", "jsonschema", b"{}")
        cid = w.register_channel("/x", "json", sid)
        w.add_message(cid, 0, b"{}", 0)
        w.finish()
    with pytest.raises(DatasetError, match="not a naoloc survey dataset"):
        read_dataset(path)


def test_empty_survey_says_no_frames(tmp_path: Path) -> None:
    path = tmp_path / "empty.mcap"
    writer = DatasetWriter(path, config={}, meta={})
    writer._file.flush()  # died before its first frame
    assert not writer.partial_path.exists()  # the file takes that name at the first frame
    with pytest.raises(DatasetError, match="no frames"):
        read_dataset(writer._file.name)


def test_a_run_without_frames_keeps_the_existing_dataset(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    _write(path, 3)
    before = path.read_bytes()
    _write(path, 2, complete=False)  # an interrupted run...
    partial = partial_path_for(path).read_bytes()
    DatasetWriter(path, config={}, meta={}).close(complete=False)  # ...then one that failed at once
    assert path.read_bytes() == before
    assert partial_path_for(path).read_bytes() == partial  # the earlier partial is kept too
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.mcap", "s.partial.mcap"]
    _write(path, 2)  # a complete run with frames replaces it
    assert len(read_dataset(path).keyframes) == 2


def test_missing_dataset_points_at_the_partial_one(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    _write(path, 2, complete=False)
    with pytest.raises(DatasetError, match=r"s.mcap: no such dataset; .*s.partial.mcap"):
        read_dataset(path)


def test_flipped_byte_is_a_dataset_error(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    _write(path, 2)
    raw = path.read_bytes()
    assert json.dumps(-1.57).encode() not in raw  # the records are compressed
    middle = len(raw) // 2
    path.write_bytes(raw[:middle] + bytes([raw[middle] ^ 0x40]) + raw[middle + 1 :])
    with pytest.raises(DatasetError, match=f"{path}: corrupt MCAP at byte") as info:
        read_dataset(path)
    assert "\n" not in str(info.value)


def test_newer_version_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    _write(path, 1, finish=False)  # no data-section CRC yet, so the edit is not a CRC error
    part = partial_path_for(path)
    raw = part.read_bytes()
    version = b"\x07\x00\x00\x00version\x01\x00\x00\x00" + str(FORMAT_VERSION).encode()
    assert raw.count(version) == 1  # the one-digit version string with its length
    part.write_bytes(raw.replace(version, version[:-1] + b"9"))
    with pytest.raises(DatasetError, match="newer"):
        read_dataset(part)


def test_closed_writer_refuses_frames(tmp_path: Path) -> None:
    w = DatasetWriter(tmp_path / "s.mcap", config={}, meta={})
    w.close()
    w.close()  # idempotent
    with pytest.raises(DatasetError, match="closed"):
        w.write(_keyframe(0, np.random.default_rng(0)))


def test_nonfinite_pose_is_refused_on_read(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    rng = np.random.default_rng(0)
    kf = _keyframe(0, rng)
    bad = Keyframe(kf.image, Pose2D(math.inf, 0.0, 0.0), camera=kf.camera)
    with DatasetWriter(path, config={}, meta={}) as w:
        w.write(bad)
    with pytest.raises(DatasetError):
        read_dataset(path)


def test_far_pictures_round_trip_beside_their_stops(tmp_path: Path) -> None:
    """Far pictures (the room across its interior) are kept apart from the wall pictures,
    each with the wall picture it was taken beside; the wall pictures read as before."""
    path = tmp_path / "s.mcap"
    rng = np.random.default_rng(1)
    walls = [_keyframe(i, rng) for i in range(3)]
    far = [dataclasses.replace(_keyframe(10 + i, rng), head_yaw=1.3) for i in range(2)]
    writer = DatasetWriter(path, config={}, meta=META)
    writer.write(walls[0])
    writer.write(far[0], stop=0)
    writer.write(walls[1])
    writer.write(walls[2])
    writer.write(far[1], stop=2)
    with pytest.raises(DatasetError, match="stop 3 is not one of the 3 wall pictures"):
        writer.write(far[1], stop=3)
    writer.close()
    data = read_dataset(path)
    assert [kf.pose for kf in data.keyframes] == [kf.pose for kf in walls]
    assert [(s, kf.pose, kf.head_yaw) for s, kf in data.far] == [
        (0, far[0].pose, 1.3),
        (2, far[1].pose, 1.3),
    ]
    assert data.meta["frames"] == 3 and data.meta["far_frames"] == 2 and writer.frames == 5


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        ({"view": "far", "stop": 1}, r"stop is 1, outside \[0, 0\]"),
        ({"view": "far"}, "stop must be an integer"),
        ({"view": "sideways"}, "view must be 'wall' or 'far'"),
    ],
)
def test_a_far_picture_must_name_a_wall_picture_before_it(
    tmp_path: Path, edit: dict[str, object], message: str
) -> None:
    path = tmp_path / "s.mcap"
    rng = np.random.default_rng(2)
    writer = DatasetWriter(path, config={}, meta=META)
    writer.write(_keyframe(0, rng))
    real = writer._add

    def tampered(topic: str, stamp: float, data: bytes) -> None:
        if topic == "/naoloc/keyframe":
            data = json.dumps({**json.loads(data), **edit}).encode()
        real(topic, stamp, data)

    writer._add = tampered  # type: ignore[method-assign]
    writer.write(_keyframe(1, rng))
    writer.close()
    with pytest.raises(DatasetError, match=f"frame 1: {message}"):
        read_dataset(path)
