"""ROS 2 without ROS: datasets and recordings as ROS 2 MCAP, and naoqi_driver2 recordings read.

:func:`write_ros2` writes a naoloc dataset or recording as an MCAP file of the ``ros2``
profile with CDR-encoded ROS 2 messages (through the ``mcap-ros2-support`` library), the
topics and frames naoqi_driver2 publishes for a NAO, so ``ros2 bag info`` and Foxglove
read it:

- ``/camera/front/image_raw`` ``sensor_msgs/msg/Image`` (``bgr8`` or ``mono8``), frame
  ``CameraTop_optical_frame``, and ``/camera/front/camera_info``
  ``sensor_msgs/msg/CameraInfo`` (naoloc's lens: K scaled to the image, plumb_bob k1);
- ``/odom`` ``nav_msgs/msg/Odometry``, ``odom -> base_footprint``;
- ``/tf`` ``tf2_msgs/msg/TFMessage``: ``map -> odom -> base_footprint -> CameraTop_frame
  -> CameraTop_optical_frame`` (REP-105; the camera from the robot's own kinematics);
- ``/joint_states`` ``sensor_msgs/msg/JointState``: HeadYaw and HeadPitch;
- a recording's estimates on ``/pose/estimate``
  ``geometry_msgs/msg/PoseWithCovarianceStamped``, frame ``map``.

:func:`read_ros2_survey` reads such a recording (naoqi_driver2's own, or ours) back as a
survey :class:`~naoloc.data.dataset.Dataset`: each camera image with the odometry, head
angles and camera transform nearest its stamp, poses relative to the first image's
odometry (the map frame). It carries none of naoloc's survey facts (floor lines, corners),
so ``build-map`` builds the odometry's map from it (``--keep-unchecked``).
"""

from __future__ import annotations

import bisect
import math
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.errors import DatasetError
from naoloc.geometry import Pose2D

PROFILE = "ros2"
IMAGE_TOPIC = "/camera/front/image_raw"
INFO_TOPIC = "/camera/front/camera_info"
CAMERA_FRAME = "CameraTop_frame"
OPTICAL_FRAME = "CameraTop_optical_frame"
BASE_FRAME = "base_footprint"
MAX_IMAGES = 20_000  # images read from a ROS 2 recording at most

# ROS 2 message definitions (Humble), each with the types it uses.
_DEFS: dict[str, tuple[str, tuple[str, ...]]] = {
    "builtin_interfaces/Time": ("int32 sec\nuint32 nanosec", ()),
    "std_msgs/Header": (
        "builtin_interfaces/Time stamp\nstring frame_id",
        ("builtin_interfaces/Time",),
    ),
    "geometry_msgs/Vector3": ("float64 x\nfloat64 y\nfloat64 z", ()),
    "geometry_msgs/Point": ("float64 x\nfloat64 y\nfloat64 z", ()),
    "geometry_msgs/Quaternion": ("float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1", ()),
    "geometry_msgs/Pose": (
        "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation",
        ("geometry_msgs/Point", "geometry_msgs/Quaternion"),
    ),
    "geometry_msgs/PoseWithCovariance": (
        "geometry_msgs/Pose pose\nfloat64[36] covariance",
        ("geometry_msgs/Pose",),
    ),
    "geometry_msgs/Twist": (
        "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular",
        ("geometry_msgs/Vector3",),
    ),
    "geometry_msgs/TwistWithCovariance": (
        "geometry_msgs/Twist twist\nfloat64[36] covariance",
        ("geometry_msgs/Twist",),
    ),
    "geometry_msgs/Transform": (
        "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation",
        ("geometry_msgs/Vector3", "geometry_msgs/Quaternion"),
    ),
    "geometry_msgs/TransformStamped": (
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform",
        ("std_msgs/Header", "geometry_msgs/Transform"),
    ),
    "geometry_msgs/PoseWithCovarianceStamped": (
        "std_msgs/Header header\ngeometry_msgs/PoseWithCovariance pose",
        ("std_msgs/Header", "geometry_msgs/PoseWithCovariance"),
    ),
    "tf2_msgs/TFMessage": (
        "geometry_msgs/TransformStamped[] transforms",
        ("geometry_msgs/TransformStamped",),
    ),
    "nav_msgs/Odometry": (
        "std_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist",
        (
            "std_msgs/Header",
            "geometry_msgs/PoseWithCovariance",
            "geometry_msgs/TwistWithCovariance",
        ),
    ),
    "sensor_msgs/Image": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
        "uint8 is_bigendian\nuint32 step\nuint8[] data",
        ("std_msgs/Header",),
    ),
    "sensor_msgs/RegionOfInterest": (
        "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify",
        (),
    ),
    "sensor_msgs/CameraInfo": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
        "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n"
        "uint32 binning_y\nsensor_msgs/RegionOfInterest roi",
        ("std_msgs/Header", "sensor_msgs/RegionOfInterest"),
    ),
    "sensor_msgs/JointState": (
        "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
        "float64[] effort",
        ("std_msgs/Header",),
    ),
}
_SEPARATOR = "=" * 80


def msgdef(name: str) -> str:
    """The concatenated ROS 2 message definition of ``name`` (``pkg/Type``) with every type
    it uses, as ``ros2 bag`` stores it."""
    order: list[str] = []

    def visit(n: str) -> None:
        for dep in _DEFS[n][1]:
            if dep not in order:
                visit(dep)
                if dep not in order:
                    order.append(dep)

    visit(name)
    parts = [_DEFS[name][0]]
    parts += [f"{_SEPARATOR}\nMSG: {dep}\n{_DEFS[dep][0]}" for dep in order]
    return "\n".join(parts)


def _ros_name(name: str) -> str:
    pkg, _, msg = name.partition("/")
    return f"{pkg}/msg/{msg}"


def _time(stamp: float) -> dict[str, int]:
    ns = max(0, round(stamp * 1e9))
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def _header(stamp: float, frame: str) -> dict[str, Any]:
    return {"stamp": _time(stamp), "frame_id": frame}


def _quat(r: np.ndarray) -> dict[str, float]:
    from naoloc.data.dataset import _rotation_to_quaternion

    x, y, z, w = _rotation_to_quaternion(r)
    return {"x": x, "y": y, "z": z, "w": w}


def _planar(pose: Pose2D) -> tuple[dict[str, float], dict[str, float]]:
    t = {"x": pose.x, "y": pose.y, "z": 0.0}
    q = {"x": 0.0, "y": 0.0, "z": math.sin(pose.theta / 2), "w": math.cos(pose.theta / 2)}
    return t, q


def _tf(stamp: float, parent: str, child: str, t: dict[str, float], q: dict[str, float]) -> Any:
    return {
        "header": _header(stamp, parent),
        "child_frame_id": child,
        "transform": {"translation": t, "rotation": q},
    }


# NAOqi camera frame (x forward, y left, z up) -> ROS optical frame (z forward, x right, y down).
_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def write_ros2(source: str | Path, output: str | Path) -> int:
    """Write a naoloc dataset or recording as a ROS 2 MCAP (see the module doc).

    Args:
        source: A survey dataset or a ``--record`` recording (naoloc's MCAP).
        output: The ROS 2 MCAP to write.

    Returns:
        The number of images written.

    Raises:
        DatasetError: ``source`` does not read, or ``output`` cannot be written.
    """
    from mcap_ros2.writer import Writer

    from naoloc.data.dataset import calibration, read_dataset
    from naoloc.robot.lens import Lens

    data = read_dataset(source)
    lens = Lens.from_dict(data.meta.get("lens"))
    estimates = _estimates(source) if data.meta.get("recording") else []
    try:
        stream = open(output, "wb")  # noqa: SIM115 - closed below, after finish()
    except OSError as err:
        raise DatasetError(f"{output}: cannot create: {err.strerror}") from None
    with stream:
        writer = Writer(stream)
        schemas = {
            name: writer.register_msgdef(_ros_name(name), msgdef(name))
            for name in (
                "sensor_msgs/Image", "sensor_msgs/CameraInfo", "nav_msgs/Odometry",
                "tf2_msgs/TFMessage", "sensor_msgs/JointState",
                "geometry_msgs/PoseWithCovarianceStamped",
            )
        }  # fmt: skip

        def put(topic: str, kind: str, stamp: float, message: Any) -> None:
            t = max(0, round(stamp * 1e9))
            writer.write_message(topic, schemas[kind], message, log_time=t, publish_time=t)

        pending = list(estimates)
        for kf in [*data.keyframes, *(k for _, k in data.far)]:
            stamp = kf.stamp
            while pending and pending[0][0] <= stamp:
                when, msg = pending.pop(0)
                put("/pose/estimate", "geometry_msgs/PoseWithCovarianceStamped", when, msg)
            image = np.ascontiguousarray(kf.image)
            colour = image.ndim == 3
            put(IMAGE_TOPIC, "sensor_msgs/Image", stamp, {
                "header": _header(stamp, OPTICAL_FRAME), "height": image.shape[0],
                "width": image.shape[1], "encoding": "bgr8" if colour else "mono8",
                "is_bigendian": 0, "step": image.shape[1] * (3 if colour else 1),
                "data": image.tobytes(),
            })  # fmt: skip
            k, d = calibration(kf.camera, lens)
            put(INFO_TOPIC, "sensor_msgs/CameraInfo", stamp, {
                "header": _header(stamp, OPTICAL_FRAME), "height": kf.camera.height,
                "width": kf.camera.width, "distortion_model": "plumb_bob", "d": d, "k": k,
                "r": [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
                "p": [k[0], 0, k[2], 0, 0, k[4], k[5], 0, 0, 0, 1.0, 0],
                "binning_x": 0, "binning_y": 0,
                "roi": {"x_offset": 0, "y_offset": 0, "height": 0, "width": 0, "do_rectify": False},
            })  # fmt: skip
            t, q = _planar(kf.pose)
            put("/odom", "nav_msgs/Odometry", stamp, {
                "header": _header(stamp, "odom"), "child_frame_id": BASE_FRAME,
                "pose": {"pose": {"position": t, "orientation": q}, "covariance": [0.0] * 36},
                "twist": {"twist": {"linear": {}, "angular": {}}, "covariance": [0.0] * 36},
            })  # fmt: skip
            cam = _camera_frame(kf)
            zero = {"x": 0.0, "y": 0.0, "z": 0.0}
            transforms = [
                _tf(stamp, "map", "odom", zero, _quat(np.eye(3))),
                _tf(stamp, "odom", BASE_FRAME, t, q),
                _tf(stamp, BASE_FRAME, CAMERA_FRAME,
                    {"x": cam[0, 3], "y": cam[1, 3], "z": cam[2, 3]}, _quat(cam[:3, :3])),
                _tf(stamp, CAMERA_FRAME, OPTICAL_FRAME, zero, _quat(_OPTICAL)),
            ]  # fmt: skip
            put("/tf", "tf2_msgs/TFMessage", stamp, {"transforms": transforms})
            put("/joint_states", "sensor_msgs/JointState", stamp, {
                "header": _header(stamp, ""), "name": ["HeadYaw", "HeadPitch"],
                "position": [kf.head_yaw, kf.head_pitch], "velocity": [], "effort": [],
            })  # fmt: skip
        for when, msg in pending:
            put("/pose/estimate", "geometry_msgs/PoseWithCovarianceStamped", when, msg)
        writer.finish()
    return len(data.keyframes) + len(data.far)


def _camera_frame(kf: Any) -> np.ndarray:
    """The camera's NAOqi frame (x forward, y left, z up) in FRAME_ROBOT, 4 x 4: the
    keyframe's own kinematics, else its optical frame turned back."""
    if kf.camera_pose is not None:
        return np.asarray(kf.camera_pose, dtype=np.float64).reshape(4, 4)
    back = np.eye(4)
    back[:3, :3] = _OPTICAL.T
    return np.asarray(kf.camera_matrix() @ back)


def _estimates(source: str | Path) -> list[tuple[float, dict[str, Any]]]:
    """A recording's estimates as PoseWithCovarianceStamped messages, by stamp."""
    import json

    from mcap.records import Channel, Message

    from naoloc.data.mcapread import read_records
    from naoloc.data.recording import OBSERVATION_TOPIC

    topics: dict[int, str] = {}
    out: list[tuple[float, dict[str, Any]]] = []
    for rec in read_records(Path(source)):
        if isinstance(rec, Channel):
            topics[rec.id] = rec.topic
        elif isinstance(rec, Message) and topics.get(rec.channel_id) == OBSERVATION_TOPIC:
            est = json.loads(rec.data).get("estimate") or {}
            if est.get("x") is None:
                continue
            stamp = rec.log_time / 1e9
            t, q = _planar(Pose2D(est["x"], est["y"], est["theta"]))
            cov = np.zeros((6, 6))
            if est.get("covariance") is not None:
                index = (0, 1, 5)  # x, y, rotation about z
                cov[np.ix_(index, index)] = np.asarray(est["covariance"], float).reshape(3, 3)
            out.append((stamp, {
                "header": _header(stamp, "map"),
                "pose": {"pose": {"position": t, "orientation": q},
                         "covariance": cov.ravel().tolist()},
            }))  # fmt: skip
    return out


def is_ros2(path: str | Path) -> bool:
    """True when ``path`` is an MCAP file of the ``ros2`` profile (a ROS 2 bag)."""
    from mcap.reader import make_reader

    if not Path(path).is_file():  # never open a FIFO or a device: the reader refuses those
        return False
    try:
        with open(path, "rb") as f:
            return bool(make_reader(f).get_header().profile == PROFILE)
    except Exception:  # not MCAP, unreadable: the naoloc reader says why in one line
        return False


def _stamp_of(message: Any, log_time: int) -> float:
    header = getattr(message, "header", None)
    stamp = getattr(header, "stamp", None)
    if stamp is None:
        return log_time / 1e9
    return float(stamp.sec) + float(stamp.nanosec) / 1e9


def _matrix(transform: Any) -> np.ndarray:
    t, q = transform.translation, transform.rotation
    x, y, z, w = (float(q.x), float(q.y), float(q.z), float(q.w))
    n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
    x, y, z, w = x / n, y / n, z / n, w / n
    m = np.eye(4)
    m[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    m[:3, 3] = [float(t.x), float(t.y), float(t.z)]
    return m


def _nearest(times: list[float], t: float) -> int:
    i = bisect.bisect_left(times, t)
    if i == 0:
        return 0
    if i == len(times):
        return len(times) - 1
    return i if times[i] - t < t - times[i - 1] else i - 1


def _decode_image(message: Any, kind: str) -> np.ndarray:
    import cv2

    if kind == "sensor_msgs/msg/CompressedImage":
        image = cv2.imdecode(np.frombuffer(bytes(message.data), np.uint8), cv2.IMREAD_COLOR)
        if image is None:
            raise DatasetError("a compressed image does not decode")
        return np.asarray(image)
    h, w, enc = int(message.height), int(message.width), str(message.encoding)
    layers = {"bgr8": 3, "rgb8": 3, "mono8": 1}.get(enc)
    if layers is None:
        raise DatasetError(f"image encoding {enc!r}: bgr8, rgb8 or mono8 expected")
    raw = np.frombuffer(bytes(message.data), np.uint8)
    step = int(message.step) or w * layers
    if not (0 < h <= 4096 and 0 < w <= 4096) or raw.size < step * h or step < w * layers:
        raise DatasetError(f"an image of {w} x {h} px has {raw.size} bytes")
    pixels = raw[: step * h].reshape(h, step)[:, : w * layers].reshape(h, w, layers)
    if enc == "mono8":
        return np.ascontiguousarray(pixels[:, :, 0])
    return np.ascontiguousarray(pixels[:, :, ::-1] if enc == "rgb8" else pixels)


def read_ros2_survey(path: str | Path) -> Any:
    """A ROS 2 recording of a NAO (camera, odometry, tf; naoqi_driver2's topics or any with
    those message types) as a survey :class:`~naoloc.data.dataset.Dataset`.

    Each camera image becomes a keyframe with the odometry (``nav_msgs/Odometry``), the
    head angles (``sensor_msgs/JointState``) and the camera's transform from
    ``base_footprint`` (else ``base_link``) on ``/tf`` and ``/tf_static`` nearest its stamp;
    the poses are in the map frame: through ``/tf``'s ``map -> odom`` at the first image
    when the recording has one (``--format ros2``), else relative to the first image's
    odometry. The camera model
    and lens come from ``sensor_msgs/CameraInfo``.

    Raises:
        DatasetError: One line naming the file: no images, no odometry, no camera info, no
            transform from the robot's base to the camera, or a message that does not
            decode.
    """
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    from naoloc.data.dataset import Dataset
    from naoloc.robot.keyframe import CameraInfo, Keyframe
    from naoloc.robot.lens import VGA, Lens

    path = Path(path)
    images: list[tuple[float, Any, str]] = []
    infos: dict[str, Any] = {}
    odom: list[tuple[float, Pose2D]] = []
    joints: list[tuple[float, dict[str, float]]] = []
    tfs: list[tuple[float, str, str, np.ndarray]] = []
    try:
        with open(path, "rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            for schema, _channel, record, msg in reader.iter_decoded_messages(log_time_order=True):
                kind = schema.name if schema is not None else ""
                t = _stamp_of(msg, record.log_time)
                if kind in ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"):
                    if len(images) < MAX_IMAGES:
                        images.append((t, msg, kind))
                elif kind == "sensor_msgs/msg/CameraInfo":
                    infos[str(msg.header.frame_id)] = msg
                elif kind == "nav_msgs/msg/Odometry":
                    p, q = msg.pose.pose.position, msg.pose.pose.orientation
                    yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
                    odom.append((t, Pose2D(float(p.x), float(p.y), yaw)))
                elif kind == "sensor_msgs/msg/JointState":
                    joints.append((t, dict(zip(msg.name, msg.position, strict=False))))
                elif kind == "tf2_msgs/msg/TFMessage":
                    static = _channel.topic == "/tf_static"
                    for tr in msg.transforms:
                        when = -math.inf if static else _stamp_of(tr, record.log_time)
                        m = _matrix(tr.transform)
                        tfs.append((when, str(tr.header.frame_id), str(tr.child_frame_id), m))
    except DatasetError:
        raise
    except Exception as err:  # the mcap and CDR readers raise their own types
        raise DatasetError(f"{path}: not a readable ROS 2 recording: {err}") from None
    if not images:
        raise DatasetError(f"{path}: no sensor_msgs/Image or CompressedImage messages")
    if not odom:
        raise DatasetError(f"{path}: no nav_msgs/Odometry messages")
    odom.sort(key=lambda o: o[0])
    joints.sort(key=lambda j: j[0])
    tfs.sort(key=lambda tr: tr[0])
    odom_t, joint_t = [o[0] for o in odom], [j[0] for j in joints]
    latest: dict[str, tuple[str, np.ndarray]] = {}
    keyframes: list[Keyframe] = []
    lens: Lens | None = None
    origin: Pose2D | None = None
    k = 0
    for t, msg, kind in sorted(images, key=lambda i: i[0]):
        while k < len(tfs) and tfs[k][0] <= t:
            latest[tfs[k][2]] = (tfs[k][1], tfs[k][3])
            k += 1
        frame = str(msg.header.frame_id)
        info = infos.get(frame)
        if info is None:
            raise DatasetError(f"{path}: no sensor_msgs/CameraInfo for the frame {frame!r}")
        camera_pose = _chain(latest, frame)
        if camera_pose is None:
            raise DatasetError(
                f"{path}: no transform from base_footprint or base_link to {frame!r}"
            )
        image = _decode_image(msg, kind)
        h, w = image.shape[:2]
        fx, fy, cx, cy = (float(info.k[i]) for i in (0, 4, 2, 5))
        if not (fx > 0 and fy > 0):
            raise DatasetError(f"{path}: the camera info of {frame!r} has no focal length")
        if lens is None:
            sx, sy = w / VGA[0], h / VGA[1]
            k1 = float(info.d[0]) if len(info.d) else 0.0
            lens = Lens(fx / sx, fy / sy, (cx - (sx - 1) / 2) / sx, (cy - (sy - 1) / 2) / sy, k1)
        camera = CameraInfo(w, h, 2 * math.atan(w / 2 / fx), 2 * math.atan(h / 2 / fy), 0)
        odometry = odom[_nearest(odom_t, t)][1]
        in_map = latest.get("odom")
        if origin is None:  # the map frame: /tf's map -> odom, else the first odometry
            origin = _planar_of(in_map[1]).inverse() if in_map and in_map[0] == "map" else odometry
        head = joints[_nearest(joint_t, t)][1] if joints else {}
        keyframes.append(
            Keyframe(
                image=image,
                pose=(origin.inverse() * odometry).normalized(),
                head_yaw=float(head.get("HeadYaw", 0.0)),
                head_pitch=float(head.get("HeadPitch", 0.0)),
                camera=camera,
                stamp=t,
                camera_pose=tuple(float(v) for v in camera_pose.ravel()),
            )
        )
    meta = {
        "source": "ros2",
        "lens": None if lens is None else lens.to_dict(),
        "origin_odometry": None if origin is None else origin.to_list(),
        "frames": len(keyframes),
    }
    return Dataset(keyframes, {}, meta, True, [0] * len(keyframes), [])


def _planar_of(m: np.ndarray) -> Pose2D:
    """The planar pose (x, y, yaw) of a 4 x 4 transform."""
    return Pose2D(float(m[0, 3]), float(m[1, 3]), math.atan2(float(m[1, 0]), float(m[0, 0])))


def _chain(latest: dict[str, tuple[str, np.ndarray]], frame: str) -> np.ndarray | None:
    """The camera's 4 x 4 pose in the robot's base frame, NAOqi's camera axes (x forward).

    Every frame is placed in its tree's root through the latest transforms; the base is
    base_footprint (NAOqi's FRAME_ROBOT: on the floor, under the torso) when the tree has
    it, else base_link (naoqi_driver2 hangs base_footprint below base_link). An optical
    frame (z forward) is turned back to the camera's axes.
    """

    def to_root(name: str) -> tuple[str, np.ndarray]:
        m, seen = np.eye(4), set()
        while name in latest and name not in seen:
            seen.add(name)
            parent, t = latest[name]
            m = t @ m
            name = parent
        return name, m

    root, camera = to_root(frame)
    for base in (BASE_FRAME, "base_link"):
        base_root, at = to_root(base)
        if base_root == root and (base in latest or base == root):
            m = np.linalg.inv(at) @ camera
            if "optical" in frame:
                back = np.eye(4)
                back[:3, :3] = _OPTICAL.T
                m = m @ back
            return np.asarray(m)
    return None
