"""Recordings of a localization (``--record FILE.mcap`` on localize, track, go-home) and
their replay without a robot (``naoloc replay``).

A recording is a naoloc dataset (:mod:`naoloc.data.dataset`: every picture the filter was
given as a lossless PNG on ``/camera/image`` with ``/camera/calibration`` (naoloc's lens),
``/tf`` and its ``/naoloc/keyframe`` record), so Foxglove opens it and
:func:`~naoloc.data.dataset.read_dataset` reads it, plus:

- ``/naoloc/observation`` (JSON): every observation in the order the filter took it:
  ``{"seq", "kind": "picture", "frame"}`` (the frame's index), ``{"seq", "kind": "lines",
  "lines", "odometry", "stamp"}`` or ``{"seq", "kind": "odometry", "odometry", "stamp"}``,
  each with the estimate after it (``estimate``: x, y, theta, covariance, status);
- ``/pose/estimate`` (``foxglove.PoseInFrame``) and ``/pose/estimate/odometry``
  (``foxglove.Odometry`` with the 6 x 6 pose covariance), frame ``map``: the estimate after
  each observation that has one (the live view's topics);
- ``/map/keyframes`` (``foxglove.PosesInFrame``) and ``/map/landmarks``
  (``foxglove.PointCloud``), frame ``map``: the map, once, with the first observation (the
  live view's map topics);
- metadata ``naoloc.recording``: the verb, the map file, the filter's seed and the final
  estimate (JSON).

Frames follow REP-105: ``map -> odom`` (from the estimate, once there is one) ``->
base_link`` (the raw odometry, FRAME_WORLD) ``-> camera``; ``/pose/odometry`` is in
``odom``. The recording is written as the run goes (``NAME.partial.mcap`` until it ends
well, as a survey's), so an interrupted run keeps what it saw.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.config import Config
from naoloc.data import checks
from naoloc.data.dataset import DatasetWriter, interruption_reason, read_dataset
from naoloc.errors import DatasetError
from naoloc.geometry import Pose2D
from naoloc.localization import Localizer, PoseEstimate
from naoloc.localization.observations import (
    LineScan,
    Observation,
    Odometry,
    Picture,
    Relocalize,
)
from naoloc.perception.floorline import WallLine
from naoloc.robot.camera import lens_of
from naoloc.robot.keyframe import Keyframe

OBSERVATION_TOPIC = "/naoloc/observation"
ESTIMATE_TOPIC = "/pose/estimate"
RECORDING_NAME = "naoloc.recording"
VERBS = ("localize", "track", "go-home")

__all__ = [
    "RecordedLocalizer", "Recording", "RecordingWriter", "read_recording", "recorded_localizer",
]  # fmt: skip


def estimate_json(est: PoseEstimate) -> dict[str, Any]:
    """An estimate as JSON (map frame, m and rad; exact floats)."""
    out: dict[str, Any] = {"status": str(est.status), "confidence": float(est.confidence)}
    if est.found:
        out.update(x=est.x, y=est.y, theta=est.theta)
        if est.covariance is not None:
            out["covariance"] = [[float(v) for v in row] for row in est.covariance]
    else:
        out["reason"] = est.reason
    return out


class RecordingWriter(DatasetWriter):
    """Write a localization's observations to an MCAP recording as they are made.

    Args:
        path: The ``.mcap`` file (``NAME.partial.mcap`` until :meth:`finish` says it ended
            well).
        cfg: The resolved config (stored without secrets; replay reads its filter tuning).
        verb: ``localize``, ``track`` or ``go-home``.
        map_path: The map the run localized in.
        vmap: The map (its survey poses and landmarks are recorded; its meta's
            ``origin_room_pose`` puts the room frame in ``/tf``).

    Raises:
        DatasetError: The file cannot be created.
    """

    def __init__(self, path: Path, cfg: Config, verb: str, map_path: Path, vmap: Any) -> None:
        map_meta: dict[str, Any] = vmap.meta
        meta = {
            "recording": verb,
            "map": str(map_path),
            "lens": lens_of(cfg).to_dict(),
            "origin_room_pose": map_meta.get("origin_room_pose"),
        }
        super().__init__(path, config=cfg.to_dict(), meta=meta, image_format="png")
        from foxglove import messages as fm

        schema = fm.PoseInFrame.get_schema()
        pose_schema = self._mcap.register_schema(
            name=schema.name, encoding=schema.encoding, data=bytes(schema.data)
        )
        json_schema = self._mcap.register_schema(
            name="naoloc.Observation", encoding="jsonschema", data=b'{"type": "object"}'
        )
        self._channels[OBSERVATION_TOPIC] = self._mcap.register_channel(
            topic=OBSERVATION_TOPIC, message_encoding="json", schema_id=json_schema
        )
        self._channels[ESTIMATE_TOPIC] = self._mcap.register_channel(
            topic=ESTIMATE_TOPIC, message_encoding="protobuf", schema_id=pose_schema
        )
        for topic, cls in (
            ("/map/keyframes", fm.PosesInFrame),
            ("/map/landmarks", fm.PointCloud),
            (ESTIMATE_TOPIC + "/odometry", fm.Odometry),
        ):
            sch = cls.get_schema()
            sid = self._mcap.register_schema(
                name=sch.name, encoding=sch.encoding, data=bytes(sch.data)
            )
            self._channels[topic] = self._mcap.register_channel(
                topic=topic, message_encoding="protobuf", schema_id=sid
            )
        self.verb = verb
        self.observations = 0
        self._map_odom: Pose2D | None = None
        self._vmap = vmap

    def _write_map(self, stamp: float) -> None:
        """The map's survey poses and landmarks (as the live view shows them), once."""
        from foxglove import messages as fm

        from naoloc.data.dataset import _timestamp

        def pose(x: float, y: float, theta: float) -> Any:
            q = fm.Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2))
            return fm.Pose(position=fm.Vector3(x=x, y=y, z=0.0), orientation=q)

        ts = _timestamp(stamp)
        vmap = self._vmap
        poses = np.asarray(vmap.keyframe_poses, dtype=float).reshape(-1, 3)
        poses = poses[: int(getattr(vmap, "wall_images", len(poses)))]
        frames = fm.PosesInFrame(
            timestamp=ts, frame_id="map", poses=[pose(*(float(v) for v in p)) for p in poses]
        )
        self._add("/map/keyframes", stamp, bytes(frames.encode()))
        points = np.asarray(getattr(vmap, "kp_points", np.zeros((0, 3))), np.float32)
        points = points.reshape(-1, 3)[np.all(np.isfinite(points.reshape(-1, 3)), axis=1)]
        f32 = fm.PackedElementFieldNumericType.Float32
        fields = [
            fm.PackedElementField(name=n, offset=4 * i, type=f32) for i, n in enumerate("xyz")
        ]
        cloud = fm.PointCloud(
            timestamp=ts, frame_id="map", pose=pose(0.0, 0.0, 0.0), point_stride=12,
            fields=fields, data=points.tobytes(),
        )  # fmt: skip
        self._add("/map/landmarks", stamp, bytes(cloud.encode()))

    def map_to_odom(self, keyframe: Keyframe, odometry: Pose2D) -> Pose2D | None:
        """REP-105's map -> odom from the latest estimate (None before the first)."""
        return self._map_odom

    def observe(self, obs: Observation, estimate: PoseEstimate) -> None:
        """Append one observation and the estimate the filter had after it.

        Raises:
            DatasetError: The writer is closed or the disk refused the bytes.
        """
        from naoloc.data.dataset import _pose_msg

        if estimate.found and not isinstance(obs, Relocalize):
            self._map_odom = (estimate.pose() * obs.odometry.inverse()).normalized()
        record: dict[str, Any] = {"seq": self.observations}
        if isinstance(obs, Picture):
            kf = obs.keyframe
            self.write(kf, odometry=kf.pose)  # a localization's poses are raw odometry
            record.update(kind="picture", frame=self.frames - 1)
        elif isinstance(obs, LineScan):
            record.update(
                kind="lines",
                lines=[_line_json(line) for line in obs.lines],
                odometry=obs.odometry.to_list(),
                stamp=obs.stamp,
            )
        elif isinstance(obs, Relocalize):
            record.update(kind="relocalize", stamp=obs.stamp)
        else:
            record.update(kind="odometry", odometry=obs.odometry.to_list(), stamp=obs.stamp)
        record["estimate"] = estimate_json(estimate)
        stamp = obs.stamp
        try:
            if self.observations == 0:
                self._write_map(stamp)
            self._add(OBSERVATION_TOPIC, stamp, json.dumps(record).encode())
            if estimate.found:
                self._add(ESTIMATE_TOPIC, stamp, _pose_msg(estimate.pose(), "map", stamp))
                self._add(ESTIMATE_TOPIC + "/odometry", stamp, _odometry_msg(estimate, stamp))
            if not isinstance(obs, Picture):
                self._mcap.flush()
        except OSError as err:
            raise DatasetError(f"{self.partial_path}: write failed: {err.strerror}") from None
        self.observations += 1

    def finish(
        self, estimate: PoseEstimate | None, seed: int = 0, *, complete: bool = True,
        reason: str = "",
    ) -> Path | None:  # fmt: skip
        """Write the final estimate and close (see :meth:`DatasetWriter.close`).

        Returns:
            The file written (``NAME.mcap``, or ``NAME.partial.mcap`` when the run did not
            end well), or None when no picture was taken.
        """
        if not self._closed:
            record = {
                "verb": self.verb,
                "seed": str(seed),
                "observations": str(self.observations),
                "estimate": json.dumps(None if estimate is None else estimate_json(estimate)),
            }
            try:
                self._mcap.add_metadata(RECORDING_NAME, record)
            except OSError as err:
                raise DatasetError(f"{self.partial_path}: write failed: {err.strerror}") from None
        return self.close(complete=complete, reason=reason)


class RecordedLocalizer(Localizer):
    """A :class:`~naoloc.localization.Localizer` whose every observation is recorded.

    Args:
        vmap: The map.
        cfg: Config (``localize.filter``).
        writer: Where the observations go.
    """

    def __init__(self, vmap: Any, cfg: Config, writer: RecordingWriter) -> None:
        super().__init__(vmap, cfg.localize.filter)
        self.writer = writer

    def update(self, obs: Observation) -> None:
        """Take one observation, then record it with the estimate after it."""
        super().update(obs)
        self.writer.observe(self.log[-1], self.pose())


@contextmanager
def recorded_localizer(
    path: Path, cfg: Config, verb: str, map_path: Path, vmap: Any
) -> Iterator[RecordedLocalizer]:
    """A filter whose every observation is written to ``path`` as it is made, finished with
    its last estimate. A run that fails keeps ``NAME.partial.mcap`` (its error says so).

    Args:
        path: The recording (``NAME.mcap``).
        cfg: The run's config.
        verb: What is recorded (``localize``, ``track``, ``go-home``).
        map_path: The map's file, named in the recording.
        vmap: The map.
    """
    writer = RecordingWriter(path, cfg, verb, map_path, vmap)
    loc = RecordedLocalizer(vmap, cfg, writer)
    try:
        yield loc
    except BaseException as err:
        last = loc.pose() if loc.log else None
        kept = writer.finish(last, complete=False, reason=interruption_reason(err))
        if kept is not None:
            err.add_note(f"partial recording kept in {kept}")
        raise
    writer.finish(loc.pose())


@dataclass
class Recording:
    """A recording read back.

    Attributes:
        observations: What the filter was given, in order (pictures without features).
        config: The resolved config of the run.
        meta: The dataset meta (``recording``: the verb; ``map``; ``complete``).
        estimate: The final estimate as recorded (JSON), or None.
        seed: The filter's seed.
    """

    observations: list[Observation]
    config: dict[str, Any]
    meta: dict[str, Any]
    estimate: dict[str, Any] | None
    seed: int


def read_recording(path: str | Path) -> Recording:
    """Read a recording written by :class:`RecordingWriter` (also a partial one).

    Raises:
        DatasetError: One line naming the file: not a recording, or a record that does not
            check.
    """
    from mcap.records import Channel, Message, Metadata

    from naoloc.data.mcapread import read_records

    path = Path(path)
    data = read_dataset(path)
    if data.meta.get("recording") not in VERBS:
        raise DatasetError(f"{path}: not a recording of {', '.join(VERBS)} (a survey?)")
    topics: dict[int, str] = {}
    raw: list[bytes] = []
    info: dict[str, str] = {}
    for rec in read_records(path):
        if isinstance(rec, Channel):
            topics[rec.id] = rec.topic
        elif isinstance(rec, Message) and topics.get(rec.channel_id) == OBSERVATION_TOPIC:
            raw.append(bytes(rec.data))
        elif isinstance(rec, Metadata) and rec.name == RECORDING_NAME:
            info = dict(rec.metadata)
    observations: list[Observation] = []
    for k, message in enumerate(raw):
        try:
            observations.append(_observation(message, k, data.keyframes))
        except ValueError as err:
            raise DatasetError(f"{path}: observation {k}: {err}") from None
    try:
        estimate = checks.parse_json(info.get("estimate", "null").encode(), "the estimate")
        seed = int(info.get("seed", "0"))
    except ValueError as err:
        raise DatasetError(f"{path}: naoloc.recording: {err}") from None
    if estimate is not None and not isinstance(estimate, dict):
        raise DatasetError(f"{path}: naoloc.recording: the estimate is not an object")
    return Recording(observations, data.config, data.meta, estimate, seed)


def _odometry_msg(est: PoseEstimate, stamp: float) -> bytes:
    """The estimate as ``foxglove.Odometry`` with its covariance (x, y, yaw in the 6 x 6)."""
    from foxglove import messages as fm

    from naoloc.data.dataset import _timestamp

    cov6 = np.zeros((6, 6))
    if est.covariance is not None:
        index = (0, 1, 5)  # x, y, rotation about z
        cov6[np.ix_(index, index)] = np.asarray(est.covariance, dtype=float).reshape(3, 3)
    q = fm.Quaternion(x=0.0, y=0.0, z=math.sin(est.theta / 2), w=math.cos(est.theta / 2))
    msg = fm.Odometry(
        timestamp=_timestamp(stamp), frame_id="map", body_frame_id="base_link",
        pose=fm.Pose(position=fm.Vector3(x=est.x, y=est.y, z=0.0), orientation=q),
        pose_covariance=cov6.ravel().tolist(),
    )  # fmt: skip
    return bytes(msg.encode())


def _observation(message: bytes, k: int, keyframes: list[Keyframe]) -> Observation:
    rec = checks.parse_json(message, "the record")
    if not isinstance(rec, dict):
        raise ValueError("the record must be an object")
    if checks.integer(rec.get("seq"), "seq", 0, 10**9) != k:
        raise ValueError("out of order")
    kind = rec.get("kind")
    if kind == "picture":
        frame = checks.integer(rec.get("frame"), "frame", 0, len(keyframes) - 1)
        return Picture(keyframes[frame])
    stamp = checks.number(rec.get("stamp"), "stamp", -1e12, 1e12)
    if kind == "relocalize":
        return Relocalize(stamp)
    odometry = checks.pose(rec.get("odometry"), "odometry")
    if kind == "odometry":
        return Odometry(odometry, stamp)
    if kind == "lines":
        lines = rec.get("lines")
        if not isinstance(lines, list) or len(lines) > 64:
            raise ValueError("lines must be a list of at most 64 lines")
        return LineScan(tuple(_line(v) for v in lines), odometry, stamp)
    raise ValueError(f"kind must be picture, lines, odometry or relocalize, got {str(kind)[:20]!r}")


def _line_json(line: WallLine) -> dict[str, Any]:
    """Every field of a floor-wall line, exact (a replay sees the same numbers)."""
    out = dataclasses.asdict(line)
    if line.ends_m is not None:
        out["ends_m"] = list(line.ends_m)
    return out


def _line(value: Any) -> WallLine:
    if not isinstance(value, dict):
        raise ValueError("a line must be an object")
    names = [f.name for f in dataclasses.fields(WallLine)]
    if set(value) - set(names):
        raise ValueError(f"a line has unknown fields {sorted(set(value) - set(names))[:3]}")
    ends = value.get("ends_m")
    if ends is not None:
        if not isinstance(ends, list) or len(ends) != 2:
            raise ValueError("ends_m must be two numbers")
        ends = (
            checks.number(ends[0], "ends_m", -1e3, 1e3),
            checks.number(ends[1], "ends_m", -1e3, 1e3),
        )
    number = {
        n: checks.number(value.get(n), n, -1e6, 1e6)
        for n in names
        if n not in ("inliers", "ends_m")
    }
    if not all(math.isfinite(v) for v in number.values()):
        raise ValueError("a line's numbers must be finite")
    return WallLine(
        inliers=checks.integer(value.get("inliers"), "inliers", 0, 10**7), ends_m=ends, **number
    )
