"""Live view: what a command sees and thinks, streamed to Foxglove while it works (``--live``).

A :class:`LiveView` is a small observer that commands and behaviours call: ``camera``,
``odometry``, ``estimate``, ``map`` and ``path``. The base class shows nothing (the
default, :data:`NO_LIVE`). :class:`FoxgloveLive` runs a Foxglove WebSocket server
(foxglove-sdk, protocol ``foxglove.websocket.v1``) on 127.0.0.1 and logs Foxglove messages
on these topics:

- ``/camera/image`` CompressedImage (JPEG), frame ``camera``: every picture taken;
- ``/pose/odometry`` PoseInFrame, frame ``odom`` (NAOqi FRAME_WORLD): every
  ``getRobotPosition(True)`` reading;
- ``/pose/estimate`` PoseInFrame and ``/pose/estimate/odometry`` Odometry (with the
  estimate's 6 x 6 pose covariance when it has one, zero when unknown), frame ``map``;
  ``/pose/estimates`` PosesInFrame: every estimate so far;
- ``/map/keyframes`` PosesInFrame and ``/map/landmarks`` PointCloud (x, y, z float32),
  frame ``map``;
- ``/go_home/path`` SceneUpdate: the path walked home (line), its start and end (spheres)
  and the goal, frame ``map``;
- ``/tf`` FrameTransform, REP-105: ``odom -> base_link`` with every odometry reading and
  ``map -> odom`` with every estimate (the estimate composed with the odometry's inverse).

The map topics are latched: they are sent again every :data:`LATCH_S` while the view is
open, so a viewer that connects late still gets the map. The recording of ``--record``
(:mod:`naoloc.data.recording`) carries the same topics, frames and message types.

:func:`watch` wraps a robot so that every picture and odometry reading also goes to the
view, without touching the behaviours. Timestamps are the wall clock (it is a live view).
Importing this module imports neither foxglove nor cv2.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from naoloc.errors import NaolocError
from naoloc.robot import Robot
from naoloc.robot.image import frame_from_naoqi

DEFAULT_PORT = 8765
HOST = "127.0.0.1"
TOPICS = (
    "/camera/image",
    "/pose/odometry",
    "/pose/estimate",
    "/pose/estimate/odometry",
    "/pose/estimates",
    "/map/keyframes",
    "/map/landmarks",
    "/go_home/path",
    "/tf",
)
LATCH_S = 1.0  # the map topics are sent again this often (s), for viewers that join late


class LiveError(NaolocError):
    """The live view cannot start (port taken, foxglove-sdk missing)."""


class LiveView:
    """Observer of a running command. Every method does nothing here; see FoxgloveLive."""

    def camera(self, image: np.ndarray, t: float | None = None) -> None:
        """A picture: ``(h, w)`` grey or ``(h, w, 3)`` BGR uint8; ``t`` in s (default now)."""

    def odometry(self, pose: Sequence[float], t: float | None = None) -> None:
        """An odometry reading ``(x, y, theta)`` in FRAME_WORLD (m, rad)."""

    def estimate(
        self,
        pose: Sequence[float] | None,
        t: float | None = None,
        covariance: np.ndarray | None = None,
    ) -> None:
        """A pose estimate ``(x, y, theta)`` in the map frame; None = nothing recognised.

        Args:
            pose: The estimate (m, rad), or None for a miss.
            t: Time in s (default now).
            covariance: ``(3, 3)`` covariance of x, y, theta (m^2, rad^2), when known.
        """

    def map(self, keyframes: np.ndarray, landmarks: np.ndarray | None = None) -> None:
        """The map: ``(N, 3)`` keyframe poses and ``(M, 3)`` landmarks, map frame (m, rad)."""

    def path(self, points: Sequence[Sequence[float]], goal: Sequence[float] = (0.0, 0.0)) -> None:
        """A path walked so far: ``(x, y)`` points in the map frame (m), and its goal."""

    def close(self) -> None:
        """Stop streaming. Safe to call twice."""

    def __enter__(self) -> LiveView:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


NO_LIVE = LiveView()


def _stamp(fm: Any, t: float | None) -> Any:
    t = time.time() if t is None else t
    sec = int(t)
    return fm.Timestamp(sec=sec, nsec=min(999_999_999, round((t - sec) * 1e9)))


def _pose(fm: Any, x: float, y: float, theta: float, z: float = 0.0) -> Any:
    return fm.Pose(
        position=fm.Vector3(x=float(x), y=float(y), z=float(z)),
        orientation=fm.Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2)),
    )


class FoxgloveLive(LiveView):
    """A Foxglove WebSocket server on 127.0.0.1:``port`` with naoloc's live topics.

    Open ``ws://127.0.0.1:PORT`` in Foxglove (Open connection -> Foxglove WebSocket).
    """

    def __init__(self, port: int = DEFAULT_PORT, host: str = HOST, quality: int = 80) -> None:
        try:
            import foxglove
            from foxglove import channels as fc
        except ImportError:
            raise LiveError("--live needs foxglove-sdk: pip install foxglove-sdk") from None
        self._quality = quality
        self._context = foxglove.Context()
        try:
            self._server = foxglove.start_server(
                name="naoloc", host=host, port=port, context=self._context
            )
        except Exception as err:  # the SDK raises its own error type for a taken port
            raise LiveError(f"--live: cannot listen on {host}:{port}: {err}") from None
        ctx = self._context
        self.port = int(self._server.port)
        self._image = fc.CompressedImageChannel("/camera/image", context=ctx)
        self._odometry = fc.PoseInFrameChannel("/pose/odometry", context=ctx)
        self._estimate = fc.PoseInFrameChannel("/pose/estimate", context=ctx)
        self._estimate_cov = fc.OdometryChannel("/pose/estimate/odometry", context=ctx)
        self._estimates = fc.PosesInFrameChannel("/pose/estimates", context=ctx)
        self._keyframes = fc.PosesInFrameChannel("/map/keyframes", context=ctx)
        self._landmarks = fc.PointCloudChannel("/map/landmarks", context=ctx)
        self._path = fc.SceneUpdateChannel("/go_home/path", context=ctx)
        self._tf = fc.FrameTransformChannel("/tf", context=ctx)
        self._history: list[tuple[float, float, float]] = []
        self._odom: tuple[float, float, float] | None = None
        self._latched: list[tuple[Any, Any]] = []  # (channel, message) sent again
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._latch = threading.Thread(target=self._relatch, name="naoloc-live-latch", daemon=True)
        self._latch.start()
        self._closed = False

    def _relatch(self) -> None:
        while not self._stop.wait(LATCH_S):
            with self._lock:
                latched = list(self._latched)
            for channel, message in latched:
                channel.log(message)

    def _transform(self, parent: str, child: str, pose: Sequence[float], ts: Any) -> None:
        from foxglove import messages as fm

        x, y, theta = (float(v) for v in pose[:3])
        rotation = fm.Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2.0), w=math.cos(theta / 2.0))
        self._tf.log(
            fm.FrameTransform(
                timestamp=ts, parent_frame_id=parent, child_frame_id=child,
                translation=fm.Vector3(x=x, y=y, z=0.0), rotation=rotation,
            )
        )  # fmt: skip

    def camera(self, image: np.ndarray, t: float | None = None) -> None:
        import cv2
        from foxglove import messages as fm

        ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, self._quality])
        if ok:
            self._image.log(
                fm.CompressedImage(
                    timestamp=_stamp(fm, t), frame_id="camera", data=buf.tobytes(), format="jpeg"
                )
            )

    def odometry(self, pose: Sequence[float], t: float | None = None) -> None:
        from foxglove import messages as fm

        x, y, theta = (float(v) for v in pose[:3])
        ts = _stamp(fm, t)
        self._odometry.log(
            fm.PoseInFrame(timestamp=ts, frame_id="odom", pose=_pose(fm, x, y, theta))
        )
        self._odom = (x, y, theta)
        self._transform("odom", "base_link", self._odom, ts)

    def estimate(
        self,
        pose: Sequence[float] | None,
        t: float | None = None,
        covariance: np.ndarray | None = None,
    ) -> None:
        from foxglove import messages as fm

        if pose is None or not all(math.isfinite(float(v)) for v in pose[:3]):
            return  # a miss shows as no new estimate
        x, y, theta = (float(v) for v in pose[:3])
        ts = _stamp(fm, t)
        self._estimate.log(
            fm.PoseInFrame(timestamp=ts, frame_id="map", pose=_pose(fm, x, y, theta))
        )
        cov6 = np.zeros((6, 6))
        if covariance is not None:
            c = np.asarray(covariance, dtype=float).reshape(3, 3)
            index = (0, 1, 5)  # x, y, rotation about z
            cov6[np.ix_(index, index)] = c
        self._estimate_cov.log(
            fm.Odometry(
                timestamp=ts, frame_id="map", body_frame_id="base_link",
                pose=_pose(fm, x, y, theta), pose_covariance=cov6.ravel().tolist(),
            )
        )  # fmt: skip
        if self._odom is not None:  # REP-105: map -> odom = estimate * odometry^-1
            from naoloc.geometry import Pose2D

            map_odom = Pose2D(x, y, theta) * Pose2D(*self._odom).inverse()
            self._transform("map", "odom", tuple(map_odom.normalized()), ts)
        self._history.append((x, y, theta))
        self._estimates.log(
            fm.PosesInFrame(
                timestamp=ts, frame_id="map", poses=[_pose(fm, *p) for p in self._history]
            )
        )

    def map(self, keyframes: np.ndarray, landmarks: np.ndarray | None = None) -> None:
        from foxglove import messages as fm

        ts = _stamp(fm, None)
        poses = np.asarray(keyframes, dtype=float).reshape(-1, 3)
        frames = fm.PosesInFrame(timestamp=ts, frame_id="map", poses=[_pose(fm, *p) for p in poses])
        self._keyframes.log(frames)
        with self._lock:
            self._latched = [(self._keyframes, frames)]
        if landmarks is None:
            return
        points = np.asarray(landmarks, dtype=np.float32).reshape(-1, 3)
        points = points[np.isfinite(points).all(axis=1)]
        f32 = fm.PackedElementFieldNumericType.Float32
        cloud = fm.PointCloud(
            timestamp=ts, frame_id="map", pose=_pose(fm, 0.0, 0.0, 0.0), point_stride=12,
            fields=[
                fm.PackedElementField(name=n, offset=4 * i, type=f32)
                for i, n in enumerate("xyz")
            ],
            data=points.tobytes(),
        )  # fmt: skip
        self._landmarks.log(cloud)
        with self._lock:
            self._latched.append((self._landmarks, cloud))

    def path(self, points: Sequence[Sequence[float]], goal: Sequence[float] = (0.0, 0.0)) -> None:
        from foxglove import messages as fm

        pts = [(float(p[0]), float(p[1])) for p in points]
        if not pts:
            return
        ts = _stamp(fm, None)

        def sphere(x: float, y: float, rgb: tuple[float, float, float]) -> Any:
            return fm.SpherePrimitive(
                pose=_pose(fm, x, y, 0.0, z=0.05),
                size=fm.Vector3(x=0.15, y=0.15, z=0.15),
                color=fm.Color(r=rgb[0], g=rgb[1], b=rgb[2], a=1.0),
            )

        line = fm.LinePrimitive(
            type=fm.LinePrimitiveLineType.LineStrip, thickness=0.03, scale_invariant=False,
            points=[fm.Point3(x=x, y=y, z=0.02) for x, y in pts],
            color=fm.Color(r=0.1, g=0.3, b=0.9, a=1.0),
        )  # fmt: skip
        entity = fm.SceneEntity(
            timestamp=ts, frame_id="map", id="go_home_path",
            lines=[line] if len(pts) > 1 else [],
            spheres=[
                sphere(*pts[0], (0.1, 0.7, 0.1)),  # start: green
                sphere(*pts[-1], (0.1, 0.3, 0.9)),  # end so far: blue
                sphere(float(goal[0]), float(goal[1]), (0.9, 0.1, 0.1)),  # goal: red
            ],
        )  # fmt: skip
        self._path.log(fm.SceneUpdate(entities=[entity]))

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._stop.set()
        self._latch.join(timeout=2.0)
        self._server.stop()


def open_live(port: int | None) -> LiveView:
    """The live view of ``--live [PORT]``: FoxgloveLive on 127.0.0.1:PORT, or NO_LIVE."""
    if port is None:
        return NO_LIVE
    if not 0 <= port <= 65535:
        raise LiveError(f"--live: port {port} is not in 0-65535")
    return FoxgloveLive(port)


def live_from_args(args: argparse.Namespace) -> LiveView:
    """The live view a command's ``--live [PORT]`` asks for; says where on stderr.

    Raises:
        LiveError: The port cannot be listened on, or foxglove-sdk is missing.
    """
    port = getattr(args, "live", None)
    view = open_live(port)
    if isinstance(view, FoxgloveLive):
        print(
            f"naoloc: live view on ws://{HOST}:{view.port} (Foxglove WebSocket)",
            file=sys.stderr, flush=True,
        )  # fmt: skip
    return view


def show_map(view: LiveView, vmap: Any) -> None:
    """Show a :class:`naoloc.mapping.VisualMap`'s keyframes (refined poses) and landmarks."""
    if view is NO_LIVE:
        return
    poses = getattr(vmap, "refined_poses", None)
    if poses is None:
        poses = vmap.keyframe_poses
    walls = getattr(vmap, "wall_images", len(poses))  # the walk; the far pictures follow
    view.map(np.asarray(poses)[:walls], getattr(vmap, "kp_points", None))


def estimate_pose(estimate: Any) -> tuple[float, float, float] | None:
    """``(x, y, theta)`` of an estimate, or None when it is a miss (no pose, confidence 0)."""
    if estimate is None or getattr(estimate, "found", True) is False:
        return None
    values = (getattr(estimate, "x", None), getattr(estimate, "y", None))
    theta = getattr(estimate, "theta", None)
    if any(v is None for v in (*values, theta)) or not float(estimate.confidence) > 0:
        return None
    pose = (float(values[0]), float(values[1]), float(theta))  # type: ignore[arg-type]
    return pose if all(math.isfinite(v) for v in pose) else None


def show_estimate(view: LiveView, estimate: Any) -> None:
    """Show a :class:`naoloc.localization.PoseEstimate` with its 3 x 3 covariance of x, y,
    theta (none shown when it has none: unknown, never invented)."""
    cov = getattr(estimate, "covariance", None)
    view.estimate(estimate_pose(estimate), covariance=None if cov is None else np.asarray(cov))


def follow_track(view: LiveView) -> Callable[[Any], None]:
    """An ``on_point(track_point)`` callback (track, go-home) that shows each pose and the
    path of poses so far."""
    walked: list[tuple[float, float, float]] = []

    def on_point(point: Any) -> None:
        show_estimate(view, point.estimate)
        pose = estimate_pose(point.estimate)
        if pose is not None:
            walked.append(pose)
            if len(walked) % 5 == 1:
                view.path(walked)

    return on_point


class _Watched:
    """A NAOqi service that forwards every call to ``inner``; subclasses also show some."""

    def __init__(self, inner: Any, view: LiveView) -> None:
        self._inner, self._view = inner, view

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)


class _WatchedVideo(_Watched):
    """ALVideoDevice that also shows every ``getImageRemote`` picture."""

    def getImageRemote(self, handle: str) -> Any:  # noqa: N802 - mirrors ALVideoDevice
        value = self._inner.getImageRemote(handle)
        if value is not None:
            frame = frame_from_naoqi(value)
            self._view.camera(frame.gray() if frame.pixels.shape[2] == 1 else frame.bgr())
        return value


class _WatchedMotion(_Watched):
    """ALMotion that also shows every sensor odometry reading."""

    def getRobotPosition(self, use_sensors: bool) -> Any:  # noqa: N802 - mirrors ALMotion
        value = self._inner.getRobotPosition(use_sensors)
        if use_sensors:
            self._view.odometry(value)
        return value


def watch(robot: Robot, view: LiveView) -> Robot:
    """``robot`` with its pictures and odometry readings also shown on ``view``.

    The returned robot shares the backend (close the original, not this one); with
    :data:`NO_LIVE` it is ``robot`` itself.
    """
    if view is NO_LIVE or type(view) is LiveView:
        return robot
    return dataclasses.replace(
        robot,
        video=_WatchedVideo(robot.video, view),  # type: ignore[arg-type]
        motion=_WatchedMotion(robot.motion, view),  # type: ignore[arg-type]
        _closer=None,
    )
