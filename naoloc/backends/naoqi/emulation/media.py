"""ALAnimationPlayer and ALVideoRecorder of a served NAOqi.

**ALAnimationPlayer.** ``run(name)`` and ``runTag(tag)`` play the joint motion of the
animations naoloc knows (:data:`ANIMATIONS`: a wave for ``.../Hey_*`` and the tag
"hello", a nod for "yes", a head shake for "no", a short bow), with ALMotion's
angleInterpolation, blocking for their duration. An animation naoloc does not know is
a documented no-op: it blocks for :data:`UNKNOWN_S` (a typical NAO animation) without
moving, and the server's log says so once.

**ALVideoRecorder.** ``startRecording(folder, fileName[, overwrite])`` records the
simulated camera (``setCameraID``, ``setResolution``, ``setFrameRate``) into a real
Motion-JPEG ``.avi`` file until ``stopRecording()``, which returns ``[frames, path]``.
The robot's folder is mapped into the server's recording folder (``record_dir``; a
``..`` is refused), so a client never writes elsewhere on the server's disk; the
returned path is the real file.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path, PurePosixPath
from typing import Any, Final

import numpy as np

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.errors import RobotError

UNKNOWN_S: Final = 2.0
_WAVE: Final = [
    ("RShoulderPitch", [-1.0, -1.0, -1.0, -1.0, 1.4], [0.6, 1.1, 1.6, 2.1, 2.8]),
    ("RShoulderRoll", [-0.3, -0.3, -0.3, -0.3, -0.2], [0.6, 1.1, 1.6, 2.1, 2.8]),
    ("RElbowRoll", [1.2, 0.5, 1.2, 0.5, 0.4], [0.6, 1.1, 1.6, 2.1, 2.8]),
    ("RElbowYaw", [1.4, 1.4, 1.4, 1.4, 1.2], [0.6, 1.1, 1.6, 2.1, 2.8]),
]
ANIMATIONS: Final[dict[str, list[tuple[str, list[float], list[float]]]]] = {
    "hey": _WAVE,
    "hello": _WAVE,
    "yes": [("HeadPitch", [0.3, -0.1, 0.3, 0.0], [0.4, 0.8, 1.2, 1.6])],
    "no": [("HeadYaw", [0.45, -0.45, 0.45, 0.0], [0.4, 1.0, 1.6, 2.0])],
    "bow": [("HeadPitch", [0.45, 0.0], [0.8, 1.8])],
}
RECORDER_FPS: Final = (1, 30)
VIDEO_FORMATS: Final = ("MJPG",)


def _known(name: str) -> list[tuple[str, list[float], list[float]]] | None:
    """The keyframes of an animation path or tag, matched on its last word."""
    word = name.rsplit("/", 1)[-1].split("_", 1)[0].lower()
    if word in ANIMATIONS:
        return ANIMATIONS[word]
    return ANIMATIONS.get("bow") if word in ("bowshort", "bowlong") else None


class AnimationPlayerFront:
    """ALAnimationPlayer over the served ALMotion front.

    Args:
        ctx: The host's context.
        motion: The served ALMotion front (angleInterpolation).
    """

    def __init__(self, ctx: FrontContext, motion: Any) -> None:
        self._ctx, self._motion = ctx, motion
        self._stop = threading.Event()

    def _play(self, name: Any, what: str) -> None:
        if not isinstance(name, str) or not name:
            raise RobotError(f"{what} must be a non-empty string, got {name!r}")
        keys = _known(name)
        self._stop.clear()
        if keys is None:
            self._ctx.not_simulated(f"ALAnimationPlayer animation {name!r} (unknown to naoloc)")
            self._ctx.sleep_sim(UNKNOWN_S, self._stop)
            return
        if len(keys) == 1:  # one joint: NAOqi's flat form
            self._motion.angleInterpolation(keys[0][0], keys[0][1], keys[0][2], True)
            return
        names = [k[0] for k in keys]
        self._motion.angleInterpolation(names, [k[1] for k in keys], [k[2] for k in keys], True)

    def run(self, name: Any, *_: Any) -> None:
        """Play an animation by path (``animations/Stand/Gestures/Hey_1``); blocking."""
        self._play(name, "an animation path")

    def runTag(self, tag: Any, *_: Any) -> None:
        """Play an animation of a tag ("hello", "yes", "no", "bow"); blocking."""
        self._play(tag, "a tag")

    def reset(self) -> None:
        """Stop a running animation (the joints stop where they are)."""
        self._stop.set()
        self._motion.killAll()

    def declarePathForTags(self, path: Any) -> None:
        """Accepted (naoloc's animations are built in)."""

    def addTagForAnimations(self, tags: Any) -> None:
        """Accepted (naoloc's animations are built in)."""


class VideoRecorderFront:
    """ALVideoRecorder: a real video file from the served ALVideoDevice.

    Args:
        ctx: The host's context.
        video: The served ALVideoDevice front.
        record_dir: Where recordings go on the server's disk.
    """

    def __init__(self, ctx: FrontContext, video: Any, record_dir: Path) -> None:
        self._ctx, self._video, self._root = ctx, video, Path(record_dir)
        self._lock = threading.Lock()
        self._camera, self._resolution, self._fps, self._format = 0, 1, 15, "MJPG"
        self._colorspace = 13
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._frames = 0
        self._path = ""
        self._error = ""

    # ------------------------------------------------------------------ settings
    def setCameraID(self, cameraID: Any) -> None:
        """The camera to record: 0 top, 1 bottom."""
        if cameraID not in (0, 1) or isinstance(cameraID, bool):
            raise RobotError(f"camera id must be 0 or 1, got {cameraID!r}")
        self._camera = int(cameraID)

    def getCameraID(self) -> int:
        """The camera to record."""
        return self._camera

    def setResolution(self, resolution: Any) -> None:
        """The resolution id (kQVGA 1, kVGA 2...)."""
        if isinstance(resolution, bool) or resolution not in range(0, 9):
            raise RobotError(f"unknown resolution id {resolution!r}")
        self._resolution = int(resolution)

    def getResolution(self) -> int:
        """The resolution id."""
        return self._resolution

    def setFrameRate(self, frameRate: Any) -> None:
        """Frames per second, 1-30."""
        if isinstance(frameRate, bool) or not isinstance(frameRate, int | float):
            raise RobotError(f"frame rate must be a number, got {frameRate!r}")
        if not RECORDER_FPS[0] <= frameRate <= RECORDER_FPS[1]:
            raise RobotError(f"frame rate must be in [1, 30], got {frameRate}")
        self._fps = int(frameRate)

    def getFrameRate(self) -> int:
        """Frames per second."""
        return self._fps

    def setColorSpace(self, colorSpace: Any) -> None:
        """Accepted (the file is always colour)."""
        self._colorspace = int(colorSpace)

    def getColorSpace(self) -> int:
        """The colour space asked for."""
        return self._colorspace

    def setVideoFormat(self, videoFormat: Any) -> None:
        """The codec: "MJPG" (Motion-JPEG in an .avi file)."""
        if videoFormat not in VIDEO_FORMATS:
            raise RobotError(f"video format must be one of {VIDEO_FORMATS}, got {videoFormat!r}")
        self._format = str(videoFormat)

    def getVideoFormat(self) -> str:
        """The codec."""
        return self._format

    def isRecording(self) -> bool:
        """True while recording."""
        return self._thread is not None

    # ------------------------------------------------------------------ recording
    def _target(self, folder: Any, name: Any, overwrite: bool) -> Path:
        if not isinstance(folder, str) or not isinstance(name, str) or not name:
            raise RobotError("startRecording takes (folderPath, fileName[, overwrite])")
        parts = [p for p in PurePosixPath(folder).parts if p not in ("/", "")]
        if ".." in parts or "/" in name or name in (".", ".."):
            raise RobotError(f"a recording path may not leave its folder: {folder!r}, {name!r}")
        path = self._root.joinpath(*parts, name if name.endswith(".avi") else f"{name}.avi")
        if path.exists() and not overwrite:
            raise RobotError(f"{path} exists; pass overwrite=True")
        path.parent.mkdir(parents=True, exist_ok=True)
        return path

    def startRecording(self, folderPath: Any, fileName: Any, *overwrite: Any) -> None:
        """Start recording the camera into ``<record_dir>/<folderPath>/<fileName>.avi``."""
        with self._lock:
            if self._thread is not None:
                raise RobotError("ALVideoRecorder is already recording; stopRecording first")
            path = self._target(folderPath, fileName, bool(overwrite and overwrite[0]))
            handle = self._video.subscribeCamera(
                "naoloc-recorder", self._camera, self._resolution, 13, self._fps
            )
            self._stop.clear()
            self._frames, self._path, self._error = 0, str(path), ""
            self._thread = threading.Thread(
                target=self._record, args=(handle, path), name="naoloc-recorder", daemon=True
            )
            self._thread.start()

    def _record(self, handle: str, path: Path) -> None:
        import cv2

        writer: Any = None
        period = 1.0 / self._fps
        try:
            while not self._stop.is_set():
                started = time.monotonic()
                image = self._video.getImageRemote(handle)
                width, height = int(image[0]), int(image[1])
                frame = np.frombuffer(bytes(image[6]), np.uint8).reshape(height, width, 3)
                if writer is None:
                    fourcc = cv2.VideoWriter.fourcc(*self._format)
                    writer = cv2.VideoWriter(str(path), fourcc, float(self._fps), (width, height))
                    if not writer.isOpened():
                        raise RobotError(f"cannot write a video at {path}")
                writer.write(frame)
                self._frames += 1
                wall = period / self._ctx.speed - (time.monotonic() - started)
                self._stop.wait(max(0.0, wall))
        except Exception as err:  # told to the client by stopRecording
            self._error = f"{type(err).__name__}: {err}"
            self._ctx.log(f"naoloc serve: ALVideoRecorder stopped: {self._error}")
        finally:
            if writer is not None:
                writer.release()
            try:
                self._video.unsubscribe(handle)
            except Exception as err:  # the robot closed first
                self._ctx.log(f"naoloc serve: ALVideoRecorder: {err}")

    def stopRecording(self) -> list[Any]:
        """Stop; ``[number of frames, path of the file]``.

        Raises:
            RobotError: Not recording, or the recording failed (its reason).
        """
        with self._lock:
            thread, self._thread = self._thread, None
        if thread is None:
            raise RobotError("ALVideoRecorder is not recording")
        self._stop.set()
        thread.join(timeout=10.0)
        if self._error:
            raise RobotError(f"the recording failed: {self._error}")
        return [self._frames, self._path]

    def close(self) -> None:
        """Stop a running recording (server shutdown)."""
        if self._thread is not None:
            self.stopRecording()
