"""Survey datasets as MCAP files with Foxglove's message schemas.

A dataset holds, per frame: the camera image (``foxglove.CompressedImage``, JPEG or PNG),
the camera calibration (``foxglove.CameraCalibration``), the odometry pose from sensors and
from commands and, on a simulator, the true pose (``foxglove.PoseInFrame``), the transforms
map -> base_link -> camera (``foxglove.FrameTransform``), and one JSON record
(``/naoloc/keyframe``) with every number :class:`naoloc.keyframe.Keyframe` needs. The
resolved config and the survey meta (camera info, origin, room size, ...) are an MCAP
metadata record named ``naoloc``. Foxglove opens the file as is.

Frames are written unchunked and flushed one by one, so a writer that dies mid-survey
leaves every frame taken so far readable: :func:`read_dataset` streams the records and
stops quietly at a truncated tail. A frame counts once its ``/naoloc/keyframe`` record,
written last, is on disk.

Frames: ``pose`` and ``command_pose`` are in the map frame (odometry at the survey start);
``true_pose`` is in the room frame; ``odometry`` is the raw FRAME_WORLD reading.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import IO, Any

import numpy as np

from naoloc.errors import DatasetError
from naoloc.geometry import Pose2D
from naoloc.keyframe import CameraInfo, Keyframe

FORMAT_NAME = "naoloc-survey"
FORMAT_VERSION = 1
METADATA_NAME = "naoloc"
KEYFRAME_TOPIC = "/naoloc/keyframe"
IMAGE_TOPIC = "/camera/image"

_KEYFRAME_SCHEMA = {
    "title": "naoloc.Keyframe",
    "type": "object",
    "properties": {
        "index": {"type": "integer", "description": "frame number from 0"},
        "stamp": {"type": "number", "description": "capture time, s (robot clock)"},
        "lap": {"type": "integer"},
        "pose": {"type": "array", "items": {"type": "number"}, "description": "map frame"},
        "command_pose": {"type": ["array", "null"], "items": {"type": "number"}},
        "odometry": {"type": ["array", "null"], "items": {"type": "number"}},
        "true_pose": {"type": ["array", "null"], "items": {"type": "number"}},
        "head_yaw": {"type": "number", "description": "rad"},
        "head_pitch": {"type": "number", "description": "rad"},
        "camera": {"type": "object"},
        "camera_pose": {
            "type": ["array", "null"],
            "items": {"type": "number"},
            "description": "camera in FRAME_ROBOT, 4x4 row-major, from ALMotion.getTransform",
        },
    },
    "required": ["index", "pose", "head_yaw", "head_pitch", "camera"],
}


@dataclass(frozen=True)
class Dataset:
    """A survey read back from disk.

    Attributes:
        keyframes: Frames in the order taken; poses in the map frame.
        config: The resolved config the survey ran with (plain dict).
        meta: Survey facts: camera info, origin_room_pose, room_size_m, backend, ...
        complete: False when the writer died before finishing the file.
        laps: Lap number of each keyframe (0-based).
    """

    keyframes: list[Keyframe]
    config: dict[str, Any]
    meta: dict[str, Any]
    complete: bool
    laps: list[int] = field(default_factory=list)


def _stamp_ns(stamp: float) -> int:
    return max(0, round(stamp * 1e9))


def _quat_z(theta: float) -> Any:
    from foxglove.messages import Quaternion

    return Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2.0), w=math.cos(theta / 2.0))


def _pose_msg(pose: Pose2D, frame_id: str, stamp: float) -> bytes:
    from foxglove.messages import Pose, PoseInFrame, Timestamp, Vector3

    sec = int(stamp)
    ts = Timestamp(sec=sec, nsec=round((stamp - sec) * 1e9))
    p = Pose(position=Vector3(x=pose.x, y=pose.y, z=0.0), orientation=_quat_z(pose.theta))
    return bytes(PoseInFrame(timestamp=ts, frame_id=frame_id, pose=p).encode())


class DatasetWriter:
    """Write survey frames to an MCAP file as they are taken.

    Use as a context manager; the file is finished (summary written) on exit, also when an
    exception or Ctrl-C ends the block. Frames go to ``PATH.part`` first, which replaces
    ``PATH`` on close once at least one frame was written, so a run that fails before its
    first frame never destroys an existing dataset. Should the process die anyway, every
    frame already written stays readable in ``PATH.part``.

    Args:
        path: Output ``.mcap`` file (its folder is created).
        config: The resolved config (JSON-able dict) stored in the file.
        meta: JSON-able survey facts (camera info, origin_room_pose, room_size_m, ...).
        image_format: "jpeg" or "png" (lossless).
        jpeg_quality: JPEG quality 1-100.

    Raises:
        DatasetError: The file cannot be created.
    """

    def __init__(
        self,
        path: str | Path,
        *,
        config: dict[str, Any],
        meta: dict[str, Any],
        image_format: str = "jpeg",
        jpeg_quality: int = 95,
    ) -> None:
        from mcap.writer import Writer

        if image_format not in ("jpeg", "png"):
            raise DatasetError(f"image format must be jpeg or png, got {image_format!r}")
        self.path = Path(path)
        self.part_path = self.path.with_name(self.path.name + ".part")
        self.frames = 0
        self._format = image_format
        self._quality = int(jpeg_quality)
        self._closed = False
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file: IO[bytes] = open(self.part_path, "wb")  # noqa: SIM115 - see close()
        except OSError as err:
            raise DatasetError(f"{self.path}: cannot create: {err.strerror}") from None
        self._mcap = Writer(self._file, use_chunking=False, enable_crcs=True)
        self._mcap.start(profile="", library="naoloc")
        self._channels = self._register_channels()
        self._config_json = json.dumps(config)
        self._add_header(meta)
        self._file.flush()

    def _add_header(self, meta: dict[str, Any]) -> None:
        record = {
            "format": FORMAT_NAME,
            "version": str(FORMAT_VERSION),
            "config": self._config_json,
            "meta": json.dumps(meta),
        }
        self._mcap.add_metadata(METADATA_NAME, record)

    def update_meta(self, meta: dict[str, Any]) -> None:
        """Write the survey meta again, e.g. with what the survey measured on the way.

        The reader keeps the last ``naoloc`` metadata record, so a file whose writer died
        before this call still reads with the meta written at the start.

        Raises:
            DatasetError: The writer is closed or the disk refused the bytes.
        """
        if self._closed:
            raise DatasetError(f"{self.path}: dataset writer is closed")
        try:
            self._add_header(meta)
            self._file.flush()
        except OSError as err:
            raise DatasetError(f"{self.path}: write failed: {err.strerror}") from None

    def _register_channels(self) -> dict[str, int]:
        from foxglove import messages as fm

        schemas: dict[str, int] = {}
        for cls in (fm.CompressedImage, fm.CameraCalibration, fm.PoseInFrame, fm.FrameTransform):
            schema = cls.get_schema()
            schemas[cls.__name__] = self._mcap.register_schema(
                name=schema.name, encoding=schema.encoding, data=bytes(schema.data)
            )
        json_schema = self._mcap.register_schema(
            name="naoloc.Keyframe",
            encoding="jsonschema",
            data=json.dumps(_KEYFRAME_SCHEMA).encode(),
        )
        topics = {
            IMAGE_TOPIC: ("CompressedImage", "protobuf"),
            "/camera/calibration": ("CameraCalibration", "protobuf"),
            "/pose/odometry": ("PoseInFrame", "protobuf"),
            "/pose/command": ("PoseInFrame", "protobuf"),
            "/pose/truth": ("PoseInFrame", "protobuf"),
            "/tf": ("FrameTransform", "protobuf"),
        }
        channels = {
            topic: self._mcap.register_channel(
                topic=topic, message_encoding=enc, schema_id=schemas[name]
            )
            for topic, (name, enc) in topics.items()
        }
        channels[KEYFRAME_TOPIC] = self._mcap.register_channel(
            topic=KEYFRAME_TOPIC, message_encoding="json", schema_id=json_schema
        )
        return channels

    def _encode_image(self, image: np.ndarray) -> bytes:
        import cv2

        if self._format == "jpeg":
            ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, self._quality])
        else:
            ok, buf = cv2.imencode(".png", image)
        if not ok:
            raise DatasetError(f"cannot encode a {image.shape} image as {self._format}")
        return bytes(buf.tobytes())

    def _add(self, topic: str, stamp: float, data: bytes) -> None:
        t = _stamp_ns(stamp)
        self._mcap.add_message(self._channels[topic], t, data, t, sequence=self.frames)

    def write(self, keyframe: Keyframe, *, lap: int = 0, odometry: Pose2D | None = None) -> None:
        """Append one frame and flush it to disk.

        Args:
            keyframe: Image (grey or BGR), map-frame poses, head angles, camera.
            lap: Lap number (0-based).
            odometry: The raw FRAME_WORLD odometry reading, if wanted in the file.

        Raises:
            DatasetError: The writer is closed or the disk refused the bytes.
        """
        from foxglove import messages as fm

        if self._closed:
            raise DatasetError(f"{self.path}: dataset writer is closed")
        kf, stamp = keyframe, keyframe.stamp
        sec = int(stamp)
        ts = fm.Timestamp(sec=sec, nsec=round((stamp - sec) * 1e9))
        cam = kf.camera
        fmt = "jpeg" if self._format == "jpeg" else "png"
        image = fm.CompressedImage(
            timestamp=ts, frame_id="camera", data=self._encode_image(kf.image), format=fmt
        )
        k = cam.matrix().ravel().tolist()
        calib = fm.CameraCalibration(
            timestamp=ts, frame_id="camera", width=cam.width, height=cam.height,
            distortion_model="plumb_bob", D=[0.0] * 5, K=k,
            R=[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
            P=[k[0], 0, k[2], 0, 0, k[4], k[5], 0, 0, 0, 1.0, 0],
        )  # fmt: skip
        t_cam = kf.camera_matrix()
        cam_tf = _rotation_to_quaternion(t_cam[:3, :3])
        tfs = [
            fm.FrameTransform(
                timestamp=ts, parent_frame_id="map", child_frame_id="base_link",
                translation=fm.Vector3(x=kf.pose.x, y=kf.pose.y, z=0.0),
                rotation=_quat_z(kf.pose.theta),
            ),
            fm.FrameTransform(
                timestamp=ts, parent_frame_id="base_link", child_frame_id="camera",
                translation=fm.Vector3(x=t_cam[0, 3], y=t_cam[1, 3], z=t_cam[2, 3]),
                rotation=fm.Quaternion(x=cam_tf[0], y=cam_tf[1], z=cam_tf[2], w=cam_tf[3]),
            ),
        ]  # fmt: skip
        record = {
            "index": self.frames,
            "stamp": stamp,
            "lap": int(lap),
            "pose": kf.pose.to_list(),
            "command_pose": None if kf.command_pose is None else kf.command_pose.to_list(),
            "odometry": None if odometry is None else odometry.to_list(),
            "true_pose": None if kf.true_pose is None else kf.true_pose.to_list(),
            "head_yaw": kf.head_yaw,
            "head_pitch": kf.head_pitch,
            "camera": _camera_dict(cam),
            "camera_pose": None if kf.camera_pose is None else list(kf.camera_pose),
        }
        try:
            self._add(IMAGE_TOPIC, stamp, bytes(image.encode()))
            self._add("/camera/calibration", stamp, bytes(calib.encode()))
            self._add("/pose/odometry", stamp, _pose_msg(kf.pose, "map", stamp))
            if kf.command_pose is not None:
                self._add("/pose/command", stamp, _pose_msg(kf.command_pose, "map", stamp))
            if kf.true_pose is not None:
                self._add("/pose/truth", stamp, _pose_msg(kf.true_pose, "room", stamp))
            for tf in tfs:
                self._add("/tf", stamp, bytes(tf.encode()))
            self._add(KEYFRAME_TOPIC, stamp, json.dumps(record).encode())
            self._file.flush()
        except OSError as err:
            raise DatasetError(f"{self.path}: write failed: {err.strerror}") from None
        self.frames += 1

    def close(self) -> None:
        """Finish the file (summary and footer) and close it. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        try:
            self._mcap.finish()
        finally:
            self._file.close()
            if self.frames > 0:
                os.replace(self.part_path, self.path)
            else:
                self.part_path.unlink(missing_ok=True)

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


def _camera_dict(cam: CameraInfo) -> dict[str, Any]:
    return {
        "width": cam.width,
        "height": cam.height,
        "hfov": cam.hfov,
        "vfov": cam.vfov,
        "index": cam.index,
    }


def _rotation_to_quaternion(r: np.ndarray) -> tuple[float, float, float, float]:
    """``(x, y, z, w)`` of a proper 3x3 rotation matrix."""
    w = math.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2.0
    x = math.copysign(
        math.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2.0, r[2, 1] - r[1, 2]
    )
    y = math.copysign(
        math.sqrt(max(0.0, 1.0 - r[0, 0] + r[1, 1] - r[2, 2])) / 2.0, r[0, 2] - r[2, 0]
    )
    z = math.copysign(
        math.sqrt(max(0.0, 1.0 - r[0, 0] - r[1, 1] + r[2, 2])) / 2.0, r[1, 0] - r[0, 1]
    )
    return (x, y, z, w)


def _protobuf_fields(data: bytes) -> dict[int, list[Any]]:
    """Top-level fields of a protobuf message: number -> values (ints or bytes).

    Raises:
        DatasetError: The bytes are not a valid protobuf message.
    """
    out: dict[int, list[Any]] = {}
    i, n = 0, len(data)

    def varint() -> int:
        nonlocal i
        shift = value = 0
        while True:
            if i >= n or shift > 63:
                raise DatasetError("corrupt protobuf message in the dataset")
            byte = data[i]
            i += 1
            value |= (byte & 0x7F) << shift
            shift += 7
            if not byte & 0x80:
                return value

    while i < n:
        key = varint()
        number, wire = key >> 3, key & 7
        if wire == 0:
            value: Any = varint()
        elif wire == 1:
            value, i = data[i : i + 8], i + 8
        elif wire == 2:
            length = varint()
            value, i = data[i : i + length], i + length
        elif wire == 5:
            value, i = data[i : i + 4], i + 4
        else:
            raise DatasetError("corrupt protobuf message in the dataset")
        if i > n:
            raise DatasetError("corrupt protobuf message in the dataset")
        out.setdefault(number, []).append(value)
    return out


def _decode_image(data: bytes, path: Path, index: int) -> np.ndarray:
    import cv2

    fields = _protobuf_fields(data)
    payload = fields.get(2, [b""])[-1]  # CompressedImage.data = 2
    image = cv2.imdecode(np.frombuffer(payload, np.uint8), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise DatasetError(f"{path}: frame {index}: image does not decode")
    return np.asarray(image)


def _records(path: Path) -> Iterator[Any]:
    """Stream MCAP records, stopping quietly at a truncated tail. Yields ``("end", ok)`` last."""
    from mcap.exceptions import InvalidMagic
    from mcap.stream_reader import StreamReader

    try:
        stream = open(path, "rb")  # noqa: SIM115 - closed below
    except FileNotFoundError:
        raise DatasetError(f"{path}: no such dataset") from None
    except OSError as err:
        raise DatasetError(f"{path}: cannot read: {err.strerror}") from None
    complete = False
    count = 0
    try:
        reader = StreamReader(stream, skip_magic=False)
        it = iter(reader.records)
        while True:
            try:
                record = next(it)
            except StopIteration:
                complete = True
                break
            except InvalidMagic:
                if count == 0:
                    raise DatasetError(f"{path}: not an MCAP file") from None
                break  # the closing magic is missing: a writer died
            except Exception:  # a truncated or garbled tail: keep what was read
                if count == 0:
                    raise DatasetError(f"{path}: not an MCAP file (empty or truncated)") from None
                break
            count += 1
            yield record
    finally:
        stream.close()
    yield ("end", complete)


def read_dataset(path: str | Path) -> Dataset:
    """Read a survey dataset, also one whose writer died mid-survey.

    Args:
        path: The ``.mcap`` file written by :class:`DatasetWriter`.

    Returns:
        The frames taken (poses in the map frame), the resolved config and the meta.

    Raises:
        DatasetError: Missing, not MCAP, not a naoloc survey, corrupt, or with no frames.
    """
    from mcap.records import Channel, Footer, Message, Metadata

    path = Path(path)
    header: dict[str, str] | None = None
    topics: dict[int, str] = {}
    images: dict[int, bytes] = {}
    records: list[dict[str, Any]] = []
    complete = False
    for rec in _records(path):
        if isinstance(rec, tuple):
            complete = bool(rec[1])
        elif isinstance(rec, Metadata) and rec.name == METADATA_NAME:
            header = dict(rec.metadata)
        elif isinstance(rec, Channel):
            topics[rec.id] = rec.topic
        elif isinstance(rec, Message):
            topic = topics.get(rec.channel_id)
            if topic == IMAGE_TOPIC:
                images[rec.sequence] = bytes(rec.data)
            elif topic == KEYFRAME_TOPIC:
                try:
                    records.append(json.loads(rec.data))
                except (ValueError, UnicodeDecodeError):
                    raise DatasetError(f"{path}: a keyframe record is not valid JSON") from None
        elif isinstance(rec, Footer):
            complete = True
    if header is None or header.get("format") != FORMAT_NAME:
        raise DatasetError(f"{path}: not a naoloc survey dataset (no '{METADATA_NAME}' metadata)")
    try:
        version = int(header.get("version", "0"))
        config = json.loads(header.get("config", "{}"))
        meta = json.loads(header.get("meta", "{}"))
    except ValueError:
        raise DatasetError(f"{path}: the naoloc metadata is not valid JSON") from None
    if version > FORMAT_VERSION:
        raise DatasetError(f"{path}: dataset format version {version} is newer than this naoloc")
    keyframes: list[Keyframe] = []
    laps: list[int] = []
    for rec in records:
        try:
            keyframe, lap = _keyframe_from_record(rec, images, path)
        except (KeyError, TypeError, ValueError):
            raise DatasetError(f"{path}: a keyframe record misses or garbles a field") from None
        if keyframe is not None:
            keyframes.append(keyframe)
            laps.append(lap)
    if not keyframes:
        raise DatasetError(f"{path}: no frames")
    return Dataset(keyframes, config, meta, complete, laps)


def _pose_or_none(value: Any) -> Pose2D | None:
    if value is None:
        return None
    pose = Pose2D.from_list(value)
    if not all(math.isfinite(v) for v in pose):
        raise ValueError("non-finite pose")
    return pose


def _camera_pose_or_none(value: Any) -> tuple[float, ...] | None:
    """The recorded 4x4 camera pose (16 floats), or None for files written without it."""
    if value is None:
        return None
    pose = tuple(float(v) for v in value)
    if len(pose) != 16 or not all(math.isfinite(v) for v in pose):
        raise ValueError("camera_pose must be 16 finite numbers")
    return pose


def _keyframe_from_record(
    rec: dict[str, Any], images: dict[int, bytes], path: Path
) -> tuple[Keyframe | None, int]:
    index = int(rec["index"])
    if index not in images:
        return None, 0
    cam = rec["camera"]
    camera = CameraInfo(
        int(cam["width"]), int(cam["height"]), float(cam["hfov"]), float(cam["vfov"]),
        int(cam.get("index", 0)),
    )  # fmt: skip
    pose = _pose_or_none(rec["pose"])
    if pose is None:
        raise ValueError("no pose")
    keyframe = Keyframe(
        image=_decode_image(images[index], path, index),
        pose=pose,
        head_yaw=float(rec["head_yaw"]),
        head_pitch=float(rec["head_pitch"]),
        camera=camera,
        stamp=float(rec.get("stamp", 0.0)),
        command_pose=_pose_or_none(rec.get("command_pose")),
        true_pose=_pose_or_none(rec.get("true_pose")),
        camera_pose=_camera_pose_or_none(rec.get("camera_pose")),
    )
    return keyframe, int(rec.get("lap", 0))
