"""Survey datasets as MCAP files with Foxglove's message schemas.

A dataset holds, per frame: the camera image (``foxglove.CompressedImage``, JPEG or PNG),
the camera calibration (``foxglove.CameraCalibration``), the odometry pose from sensors and
from commands and, on a simulator, the true pose (``foxglove.PoseInFrame``), the transforms
map -> base_link -> camera and, on a simulator, room -> map (``foxglove.FrameTransform`` on
``/tf``), and one JSON record (``/naoloc/keyframe``) with every number
:class:`naoloc.robot.keyframe.Keyframe` needs. The resolved config (without secrets) and the
survey meta (camera info, origin, room size, ...) are an MCAP metadata record named
``naoloc``; how the survey ended is a second one, ``naoloc.status``, written on close.

The file is chunked (zstd), one chunk per frame, with message and chunk indexes and CRCs
over every byte, so Foxglove opens it as is and can seek. Frames go to
``NAME.partial.mcap`` as they are taken; only a survey that completed all its laps is
renamed (atomically) to ``NAME.mcap``. An interrupted one keeps ``NAME.partial.mcap``,
marked incomplete (meta ``complete: false``, ``frames``, ``reason``), beside any complete
dataset already at ``NAME.mcap``, which is never touched. Should the process die outright,
every chunk already written stays readable in the partial file.

Reading checks before it trusts (:mod:`naoloc.data.mcapread`, :mod:`naoloc.data.checks`):
CRCs, record lengths, chunk sizes, JSON size and depth, field types and ranges, camera
models, and each image's size from its header against the camera info before decoding.
Every rejection is one line naming the file (and frame) and the problem.

Frames: ``pose`` and ``command_pose`` are in the map frame (odometry at the survey start);
``true_pose`` is in the room frame; ``odometry`` is the raw FRAME_WORLD reading. The
room -> map transform is the meta's ``origin_room_pose``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np

from naoloc.data import checks
from naoloc.data.outputs import staging_path
from naoloc.errors import DatasetError, NaolocError
from naoloc.geometry import Pose2D, modulo2PI
from naoloc.robot.keyframe import CameraInfo, Keyframe, check_camera
from naoloc.robot.lens import Lens
from naoloc.safe_yaml import refuse_non_regular

FORMAT_NAME = "naoloc-survey"
# 2: chunked and indexed, written to NAME.partial.mcap, with the naoloc.status record.
# 3: every ``meta.vision`` record names the survey side it was taken on (``side_index``).
# Older files are read through :func:`_migrate`, the one place that knows their differences.
FORMAT_VERSION = 3
METADATA_NAME = "naoloc"
STATUS_NAME = "naoloc.status"
KEYFRAME_TOPIC = "/naoloc/keyframe"
IMAGE_TOPIC = "/camera/image"
PARTIAL_SUFFIX = ".partial.mcap"
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
        config: The resolved config the survey ran with (plain dict, no secrets).
        meta: Survey facts: camera info, origin_room_pose, room_size_m, backend, ...,
            and how the survey ended: ``complete``, ``frames`` (wall pictures; ``far_frames``
            when there were far pictures) and (if incomplete)
            ``reason``.
        complete: True only when the survey completed all its laps and the file was closed.
        laps: Lap number of each keyframe (0-based).
        far: The far pictures (``survey.far_yaws_rad``: the room across its interior), each
            with its stop: the index in ``keyframes`` of the wall picture taken at the same
            place just before it. Poses in the map frame, as the keyframes'.
    """

    keyframes: list[Keyframe]
    config: dict[str, Any]
    meta: dict[str, Any]
    complete: bool
    laps: list[int] = field(default_factory=list)
    far: list[tuple[int, Keyframe]] = field(default_factory=list)


def partial_path_for(path: str | Path) -> Path:
    """Where the frames of a survey writing ``path`` go until it completes.

    ``runs/s.mcap`` -> ``runs/s.partial.mcap`` (it keeps the ``.mcap`` extension, so
    Foxglove opens it too).
    """
    path = Path(path)
    name = path.name[: -len(".mcap")] if path.name.endswith(".mcap") else path.name
    return path.with_name(name + PARTIAL_SUFFIX)


def interruption_reason(err: BaseException) -> str:
    """One phrase for what ended a survey early, e.g. ``interrupted (SIGTERM)``."""
    import signal

    if isinstance(err, KeyboardInterrupt):
        signum = getattr(err, "signum", signal.SIGINT)
        try:
            name = signal.Signals(signum).name
        except ValueError:
            name = f"signal {signum}"
        return f"interrupted ({name})"
    if isinstance(err, NaolocError):
        return str(err)
    return f"{type(err).__name__}: {err}".splitlines()[0]


def _stamp_ns(stamp: float) -> int:
    return max(0, round(stamp * 1e9))


def _timestamp(stamp: float) -> Any:
    from foxglove.messages import Timestamp

    sec = int(stamp)
    return Timestamp(sec=sec, nsec=round((stamp - sec) * 1e9))


def _quat_z(theta: float) -> Any:
    from foxglove.messages import Quaternion

    return Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2.0), w=math.cos(theta / 2.0))


def _pose_msg(pose: Pose2D, frame_id: str, stamp: float) -> bytes:
    from foxglove.messages import Pose, PoseInFrame, Vector3

    p = Pose(position=Vector3(x=pose.x, y=pose.y, z=0.0), orientation=_quat_z(pose.theta))
    return bytes(PoseInFrame(timestamp=_timestamp(stamp), frame_id=frame_id, pose=p).encode())


def _planar_tf(parent: str, child: str, pose: Pose2D, stamp: float) -> Any:
    from foxglove.messages import FrameTransform, Vector3

    return FrameTransform(
        timestamp=_timestamp(stamp), parent_frame_id=parent, child_frame_id=child,
        translation=Vector3(x=pose.x, y=pose.y, z=0.0), rotation=_quat_z(pose.theta),
    )  # fmt: skip


def calibration(cam: CameraInfo, lens: Lens | None) -> tuple[list[float], list[float]]:
    """The camera matrix K (row-major 3 x 3) and plumb_bob distortion D the images really
    have: ``lens`` scaled to the image size (naoloc's model, k1 radial), or the ideal
    pinhole of ``cam``'s field of view when there is no lens."""
    if lens is None:
        return cam.matrix().ravel().tolist(), [0.0] * 5
    fx, fy, cx, cy = lens.at(cam.width, cam.height)
    return [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0], [lens.k1, 0.0, 0.0, 0.0, 0.0]


def _origin_in_room(meta: dict[str, Any]) -> Pose2D | None:
    """The map frame's pose in the room frame (``meta["origin_room_pose"]``), if known."""
    value = meta.get("origin_room_pose")
    if value is None:
        return None
    try:
        return checks.pose(list(value), "origin_room_pose")
    except (TypeError, ValueError) as err:
        raise DatasetError(f"survey meta: {err}") from None


class DatasetWriter:
    """Write survey frames to an MCAP file as they are taken.

    Frames go to ``partial_path`` (``NAME.partial.mcap``), one zstd chunk per frame, each
    flushed as it is written. :meth:`close` finishes the file (summary, indexes, a
    ``naoloc.status`` record) and, only when told the survey is complete, renames it to
    ``path`` atomically. Used as a context manager, the survey counts as complete when the
    block ends without an exception; an exception or Ctrl-C keeps the partial file, marked
    incomplete. A run that wrote no frame leaves nothing behind (and an older partial file
    of an earlier run as it was: the file takes its name at the first frame).

    Args:
        path: Output ``.mcap`` file (its folder is created).
        config: The resolved config (JSON-able dict, e.g. ``Config.to_dict()``: no secrets).
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
        from mcap.writer import CompressionType, Writer

        if image_format not in ("jpeg", "png"):
            raise DatasetError(f"image format must be jpeg or png, got {image_format!r}")
        self.path = Path(path)
        self.partial_path = partial_path_for(self.path)
        self.frames = 0  # every picture written
        self.wall_frames = 0  # those written without a stop (wall pictures)
        self.complete = False
        self._format = image_format
        self._quality = int(jpeg_quality)
        self._closed = False
        self._origin = _origin_in_room(meta)
        self._lens = Lens.from_dict(meta.get("lens"))  # the images' own lens (calibration)
        # Until the first frame the file has a hidden name, so that a run that writes no
        # frame leaves an older partial file of an earlier run as it was.
        self._tmp_path = staging_path(self.partial_path)
        for final in (self.path, self.partial_path):  # moved into place later: never a device
            refuse_non_regular(final, DatasetError)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file: IO[bytes] = open(self._tmp_path, "wb")  # noqa: SIM115 - see close()
        except OSError as err:
            raise DatasetError(f"{self.partial_path}: cannot create: {err.strerror}") from None
        self._mcap = Writer(
            self._file, compression=CompressionType.ZSTD, enable_crcs=True, enable_data_crcs=True
        )
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
            "meta": json.dumps({**meta, "complete": False}),  # until naoloc.status says so
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
            self._lens = Lens.from_dict(meta.get("lens")) or self._lens
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

    def write(
        self,
        keyframe: Keyframe,
        *,
        lap: int = 0,
        odometry: Pose2D | None = None,
        stop: int | None = None,
    ) -> None:
        """Append one frame (one chunk) and flush it to disk.

        The frame's transforms on ``/tf``: map -> base_link (odometry), base_link -> camera
        and, when the meta has ``origin_room_pose``, room -> map (the same every frame, so a
        player that seeks anywhere has it), which puts ``/pose/truth`` (room frame) in the
        map frame.

        Args:
            keyframe: Image (grey or BGR), map-frame poses, head angles, camera.
            lap: Lap number (0-based).
            odometry: The raw FRAME_WORLD odometry reading, if wanted in the file.
            stop: For a far picture: the index among the wall pictures (frames written
                without ``stop``) of the one taken at the same place; None for a wall
                picture.

        Raises:
            DatasetError: The writer is closed, the camera model is unusable, a far
                picture names a wall picture not written yet, or the disk refused the bytes.
        """
        from foxglove import messages as fm

        if self._closed:
            raise DatasetError(f"{self.partial_path}: dataset writer is closed")
        if stop is not None and not 0 <= stop < self.wall_frames:
            raise DatasetError(
                f"{self.partial_path}: a far picture's stop {stop} is not one of the "
                f"{self.wall_frames} wall pictures written"
            )
        kf, stamp = keyframe, keyframe.stamp
        try:
            cam = check_camera(kf.camera)
        except ValueError as err:
            raise DatasetError(f"{self.partial_path}: frame {self.frames}: {err}") from None
        ts = _timestamp(stamp)
        fmt = "jpeg" if self._format == "jpeg" else "png"
        image = fm.CompressedImage(
            timestamp=ts, frame_id="camera", data=self._encode_image(kf.image), format=fmt
        )
        k, d = calibration(cam, self._lens)
        calib = fm.CameraCalibration(
            timestamp=ts, frame_id="camera", width=cam.width, height=cam.height,
            distortion_model="plumb_bob", D=d, K=k,
            R=[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
            P=[k[0], 0, k[2], 0, 0, k[4], k[5], 0, 0, 0, 1.0, 0],
        )  # fmt: skip
        t_cam = kf.camera_matrix()
        cam_tf = _rotation_to_quaternion(t_cam[:3, :3])
        tfs = [] if self._origin is None else [_planar_tf("room", "map", self._origin, stamp)]
        if odometry is None:  # no raw odometry: the pose is the only one (map frame)
            tfs.append(_planar_tf("map", "base_link", kf.pose, stamp))
        else:  # REP-105: map -> odom -> base_link, the odometry in odom
            map_odom = self.map_to_odom(kf, odometry)
            if map_odom is not None:
                tfs.append(_planar_tf("map", "odom", map_odom, stamp))
            tfs.append(_planar_tf("odom", "base_link", odometry, stamp))
        tfs += [
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
        if stop is not None:
            record.update(view="far", stop=int(stop))
        try:
            self._add(IMAGE_TOPIC, stamp, bytes(image.encode()))
            self._add("/camera/calibration", stamp, bytes(calib.encode()))
            if odometry is None:
                self._add("/pose/odometry", stamp, _pose_msg(kf.pose, "map", stamp))
            else:
                self._add("/pose/odometry", stamp, _pose_msg(odometry, "odom", stamp))
            if kf.command_pose is not None:
                self._add("/pose/command", stamp, _pose_msg(kf.command_pose, "map", stamp))
            if kf.true_pose is not None:
                self._add("/pose/truth", stamp, _pose_msg(kf.true_pose, "room", stamp))
            for tf in tfs:
                self._add("/tf", stamp, bytes(tf.encode()))
            self._add(KEYFRAME_TOPIC, stamp, json.dumps(record).encode())
            self._mcap.flush()  # ends this frame's chunk and writes it out
            if self.frames == 0:
                os.replace(self._tmp_path, self.partial_path)
        except OSError as err:
            raise DatasetError(f"{self.partial_path}: write failed: {err.strerror}") from None
        self.frames += 1
        if stop is None:
            self.wall_frames += 1

    def map_to_odom(self, keyframe: Keyframe, odometry: Pose2D) -> Pose2D | None:
        """The odom frame's pose in the map frame at this frame (REP-105's map -> odom).

        A survey's map is its odometry at the start: ``pose = map_T_odom * odometry``, so
        ``map_T_odom = pose * odometry^-1`` (constant along the survey). A recording of a
        localization overrides this with the estimate's.
        """
        return (keyframe.pose * odometry.inverse()).normalized()

    def close(self, complete: bool = True, reason: str = "") -> Path | None:
        """Finish the file (status, summary, footer) and close it. Safe to call twice.

        Args:
            complete: The survey completed all its laps: the file becomes ``path``
                (atomically replacing an older one). False keeps ``partial_path``, marked
                incomplete with ``reason``, and leaves ``path`` untouched.
            reason: Why the survey ended early (stored in ``naoloc.status``).

        Returns:
            The file the frames are in, or None when no frame was written (the partial
            file is then removed).

        Raises:
            DatasetError: The disk refused the summary (the partial file is kept).
        """
        if self._closed:
            return None if self.frames == 0 else (self.path if self.complete else self.partial_path)
        self._closed = True
        ok = complete and self.frames > 0
        status = {"complete": "true" if ok else "false", "frames": str(self.wall_frames)}
        if self.frames > self.wall_frames:
            status["far_frames"] = str(self.frames - self.wall_frames)
        if not ok:
            status["reason"] = reason or "the survey did not complete"
        finished = False
        try:
            self._mcap.add_metadata(STATUS_NAME, status)
            self._mcap.finish()
            self._file.flush()
            os.fsync(self._file.fileno())
            finished = True
        except OSError as err:
            raise DatasetError(f"{self.partial_path}: write failed: {err.strerror}") from None
        finally:
            self._file.close()
            if self.frames == 0:
                self._tmp_path.unlink(missing_ok=True)
            elif ok and finished:
                os.replace(self.partial_path, self.path)
                self.complete = True
        if self.frames == 0:
            return None
        return self.path if self.complete else self.partial_path

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, _type: object, exc: BaseException | None, _tb: object) -> None:
        self.close(complete=exc is None, reason="" if exc is None else interruption_reason(exc))


def _protobuf_fields(data: bytes) -> dict[int, list[Any]]:
    """Top-level fields of a protobuf message: number -> values (ints or bytes).

    Raises:
        ValueError: The bytes are not a valid protobuf message.
    """
    out: dict[int, list[Any]] = {}
    i, n = 0, len(data)

    def varint() -> int:
        nonlocal i
        shift = value = 0
        while True:
            if i >= n or shift > 63:
                raise ValueError("the image message is not valid protobuf")
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
            raise ValueError("the image message is not valid protobuf")
        if i > n:
            raise ValueError("the image message is not valid protobuf")
        out.setdefault(number, []).append(value)
    return out


@contextlib.contextmanager
def _quiet_stderr() -> Iterator[None]:
    """Silence file descriptor 2 (libpng and libjpeg print there on bad data)."""
    try:
        saved = os.dup(2)
    except OSError:
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _decode_image(message: bytes, camera: CameraInfo) -> np.ndarray:
    """The pixels of a CompressedImage message, sized from the header before decoding.

    Raises:
        ValueError: Not protobuf, empty, a header that disagrees with the camera or would
            decode too large, or pixels that do not decode.
    """
    import cv2

    payload = bytes(_protobuf_fields(message).get(2, [b""])[-1])  # CompressedImage.data = 2
    checks.check_image(payload, camera)
    try:
        with _quiet_stderr():
            image = cv2.imdecode(np.frombuffer(payload, np.uint8), cv2.IMREAD_UNCHANGED)
    except cv2.error:
        image = None
    if image is None:
        raise ValueError("the image does not decode")
    if image.dtype != np.uint8 or not (
        image.ndim == 2 or (image.ndim == 3 and image.shape[2] == 3)
    ):
        raise ValueError(f"the image is {image.dtype} {image.shape}; grey or BGR uint8 expected")
    if image.shape[:2] != (camera.height, camera.width):
        raise ValueError(f"the image decodes to {image.shape[1]} x {image.shape[0]} px")
    return np.asarray(image)


def read_dataset(path: str | Path) -> Dataset:
    """Read a survey dataset, also a partial one (interrupted, or its writer died).

    Args:
        path: The ``.mcap`` file written by :class:`DatasetWriter` (any format version).

    Returns:
        The frames taken (poses in the map frame), the resolved config and the meta;
        ``complete`` says whether the survey completed all its laps.

    Raises:
        DatasetError: One line naming the file: missing (and where an interrupted survey
            left its partial file), not MCAP, not a naoloc survey, corrupt, a frame or
            field that does not check, or no frames.
    """
    from mcap.records import Channel, Message, Metadata

    from naoloc.data.mcapread import StreamEnd, read_records

    path = Path(path)
    if not path.exists() and partial_path_for(path).exists():
        raise DatasetError(
            f"{path}: no such dataset; an interrupted survey left "
            f"{partial_path_for(path)}: name that file to use its frames"
        )
    from naoloc.data.ros2 import is_ros2, read_ros2_survey

    if is_ros2(path):  # a ROS 2 bag (naoqi_driver2's, or --format ros2): camera, odom, tf
        dataset: Dataset = read_ros2_survey(path)
        return dataset
    header: dict[str, str] | None = None
    status: dict[str, str] | None = None
    topics: dict[int, str] = {}
    images: dict[int, bytes] = {}
    records: list[bytes] = []
    finished = False
    for rec in read_records(path):
        if isinstance(rec, StreamEnd):
            finished = rec.finished
        elif isinstance(rec, Metadata) and rec.name == METADATA_NAME:
            header = dict(rec.metadata)  # the last one: update_meta() rewrites it at the end
        elif isinstance(rec, Metadata) and rec.name == STATUS_NAME:
            status = dict(rec.metadata)
        elif isinstance(rec, Channel):
            topics[rec.id] = rec.topic
        elif isinstance(rec, Message):
            topic = topics.get(rec.channel_id)
            if topic == IMAGE_TOPIC:
                images[rec.sequence] = bytes(rec.data)
            elif topic == KEYFRAME_TOPIC:
                records.append(bytes(rec.data))
    version, config, meta = _header(header, path)
    keyframes: list[Keyframe] = []
    laps: list[int] = []
    far: list[tuple[int, Keyframe]] = []
    seen: set[int] = set()
    for k, raw in enumerate(records):
        keyframe, lap, index, stop = _keyframe(raw, k, images, seen, path, len(keyframes))
        seen.add(index)
        if stop is None:
            keyframes.append(keyframe)
            laps.append(lap)
        else:
            far.append((stop, keyframe))
    if not keyframes:
        raise DatasetError(f"{path}: no frames")
    status = _migrate(version, meta, status, keyframes)
    complete = finished and status is not None and status.get("complete") == "true"
    meta["complete"] = complete
    if status is not None and status.get("frames", "").isdigit() and len(status["frames"]) < 10:
        meta["frames"] = int(status["frames"])
    far_count = (status or {}).get("far_frames", "")
    if far_count.isdigit() and len(far_count) < 10:
        meta["far_frames"] = int(far_count)
    if not complete:
        meta["reason"] = (status or {}).get("reason") or "the writer died before closing the file"
    return Dataset(keyframes, config, meta, complete, laps, far)


def _migrate(
    version: int, meta: dict[str, Any], status: dict[str, str] | None, keyframes: list[Keyframe]
) -> dict[str, str] | None:
    """Bring an older file's records to the current format; returns the status record.

    - 1 -> 2: version 1 wrote no status record: a closed file was a complete one.
    - 2 -> 3: ``meta.vision`` records without ``side_index`` get it from the odometry: a turn
      of more than 45 degrees between two frames starts the next side.

    Args:
        version: The file's format version.
        meta: The survey meta, changed in place.
        status: The file's status record (None: none written).
        keyframes: The survey's frames in the order taken (odometry poses, map frame).
    """
    if version < 2 and status is None:
        status = {"complete": "true"}
    vision = meta.get("vision")
    if version < 3 and isinstance(vision, list) and len(vision) == len(keyframes):
        side = 0
        for i, (entry, kf) in enumerate(zip(vision, keyframes, strict=True)):
            turned = i and abs(modulo2PI(kf.pose.theta - keyframes[i - 1].pose.theta))
            side += 1 if turned and turned > math.pi / 4 else 0
            if isinstance(entry, dict) and "side_index" not in entry:
                entry["side_index"] = side
    return status


def _header(
    header: dict[str, str] | None, path: Path
) -> tuple[int, dict[str, Any], dict[str, Any]]:
    if header is None or header.get("format") != FORMAT_NAME:
        raise DatasetError(f"{path}: not a naoloc survey dataset (no '{METADATA_NAME}' metadata)")
    text = header.get("version", "0")
    if not (text.isdigit() and len(text) <= 6):
        raise DatasetError(f"{path}: the dataset format version {text[:20]!r} is not a number")
    version = int(text)
    if version > FORMAT_VERSION:
        raise DatasetError(f"{path}: dataset format version {version} is newer than this naoloc")
    try:
        config = checks.parse_json(header.get("config", "{}").encode(), "config", "metadata")
        meta = checks.parse_json(header.get("meta", "{}").encode(), "meta", "metadata")
        if not isinstance(config, dict):
            raise ValueError(f"the config metadata must be an object, got {checks._kind(config)}")
        checks.survey_meta(meta)
    except ValueError as err:
        raise DatasetError(f"{path}: metadata: {err}") from None
    return version, config, dict(meta)


def _camera_pose_or_none(value: Any) -> tuple[float, ...] | None:
    """The recorded 4x4 camera pose (16 finite floats), or None for files written without it.

    Raises:
        ValueError: Not 16 finite numbers.
    """
    if value is None:
        return None
    if not isinstance(value, list) or len(value) != 16:
        raise ValueError("camera_pose must be a list of 16 numbers")
    return tuple(checks.number(v, "camera_pose", -1e6, 1e6) for v in value)


def _keyframe(
    raw: bytes, k: int, images: dict[int, bytes], seen: set[int], path: Path, walls: int
) -> tuple[Keyframe, int, int, int | None]:
    """Keyframe record number ``k`` checked field by field, with its image decoded; its
    stop (the wall picture it was taken beside, one of the ``walls`` read before it) when it
    is a far picture, else None."""
    where = f"keyframe record {k}"
    try:
        rec = checks.parse_json(raw, "the record")
        if not isinstance(rec, dict):
            raise ValueError(f"the record must be an object, got {checks._kind(rec)}")
        index = checks.integer(rec.get("index"), "index", 0, 10**7)
        where = f"frame {index}"
        if index in seen:
            raise ValueError("appears twice")
        camera = checks.camera(rec.get("camera"))
        checks.pose_or_none(rec.get("odometry"), "odometry")
        lap = checks.integer(rec.get("lap", 0), "lap", 0, 10**6)
        view = rec.get("view", "wall")
        if view not in ("wall", "far"):
            raise ValueError(f"view must be 'wall' or 'far', got {str(view)[:20]!r}")
        stop = None
        if view == "far":
            if walls == 0:
                raise ValueError("a far picture before any wall picture")
            stop = checks.integer(rec.get("stop"), "stop", 0, walls - 1)
        pitch_range = (-math.pi / 2, math.pi / 2)
        keyframe = Keyframe(
            image=np.zeros((0, 0), np.uint8),  # decoded below, once every field checks
            pose=checks.pose(rec.get("pose"), "pose"),
            head_yaw=checks.number(rec.get("head_yaw"), "head_yaw", -math.pi, math.pi),
            head_pitch=checks.number(rec.get("head_pitch"), "head_pitch", *pitch_range),
            camera=camera,
            stamp=checks.number(rec.get("stamp", 0.0), "stamp", -1e12, 1e12),
            command_pose=checks.pose_or_none(rec.get("command_pose"), "command_pose"),
            true_pose=checks.pose_or_none(rec.get("true_pose"), "true_pose"),
            camera_pose=_camera_pose_or_none(rec.get("camera_pose")),
        )
        if index not in images:
            raise ValueError("has no image")
        keyframe = dataclasses.replace(keyframe, image=_decode_image(images[index], camera))
    except ValueError as err:
        raise DatasetError(f"{path}: {where}: {err}") from None
    return keyframe, lap, index, stop


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
