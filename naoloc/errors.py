"""The one exception hierarchy of naoloc.

Every error that leaves the public API is a :class:`NaolocError`. Third-party
exceptions (pydantic, OpenCV, MuJoCo, zmq, qi) are caught at the boundary and
re-raised as one of these, with a one-line message that names the problem.
"""

from __future__ import annotations


class NaolocError(Exception):
    """Base of every naoloc error. ``str(err)`` is one line fit for a terminal."""


class ConfigError(NaolocError):
    """A configuration file or value is wrong: the message names the file and key path."""


class BackendError(NaolocError):
    """A backend cannot be created or used (unknown name, failed start)."""


class DependencyNotInstalled(BackendError):
    """An optional dependency is missing: the message names the pip command that fixes it."""


class RenderError(BackendError):
    """Headless rendering is unavailable: the message names the system packages to install."""


class RobotError(NaolocError):
    """A robot service refused a call (bad argument, unknown handle, wrong state)."""


class HandleError(RobotError):
    """A camera handle that does not exist or was unsubscribed."""


class MotionError(RobotError):
    """A motion could not be started or finished."""


class SurveyBlocked(MotionError):
    """The survey's walk did not happen: the robot is blocked, pressed or sliding (its
    evidence disagrees with its odometry); the partial dataset is kept, marked incomplete."""


class SurveyError(NaolocError):
    """The survey cannot start: no wall beside the robot to follow."""


class MapCheckFailed(NaolocError):
    """A map failed one of build-map's checks (``--keep-unchecked`` keeps it, unchecked)."""


class ConnectionLost(NaolocError):
    """The connection to a (real or virtual) NAOqi is dead or timed out."""


class ProtocolError(NaolocError):
    """Bytes on the wire that do not decode into a valid message."""


class OutputBusy(NaolocError):
    """An output folder is held by another running naoloc command (see ``outputs.folder_lock``)."""


class MapFormatError(NaolocError):
    """A map file is truncated, foreign, tampered with or from a newer format version."""


class DatasetError(NaolocError):
    """A survey dataset is missing, corrupt or holds no usable frames."""


class FeatureError(NaolocError):
    """Feature extraction failed (not raised for an image that merely has no keypoints)."""


class NotBuiltError(NaolocError):
    """A command or feature that does not exist yet; never silently faked."""


class UrlError(BackendError):
    """A listen or connect URL that is not ``tcp://HOST:PORT`` (or ``tcps://``)."""


class ImageError(RobotError):
    """A camera image whose size, byte count or colorspace does not add up."""


class NoEstimate(NaolocError):
    """Nothing was recognised, so there is no pose to give (``naoloc localize`` exits 3).

    Attributes:
        result: The JSON-able result line to print anyway (pose fields null, method "none").
        exit_code: The process exit code the CLI returns (3).
    """

    exit_code = 3

    def __init__(self, message: str, result: dict[str, object]) -> None:
        """An error carrying the result line to print."""
        super().__init__(message)
        self.result = result
