"""naoloc's own localization as a NAOqi service: ``NaolocLocalization``.

Choregraphe boxes and scripts in any language call it as they call ALLocalization:

- ``learnHome()``: survey the room from where the robot stands and build its map (the
  robot's start is home, the map's origin); 0 when done.
- ``localize()``: find the robot in the map from its camera; 0 when found, 1 when
  nothing was recognised.
- ``getRobotPosition()``: ``[x, y, theta]`` in the map frame (m, rad): the last fix
  carried by odometry since.
- ``goToHome()``: walk back to home, localizing on the way; 0 when there, 1 when not.
- ``isDataAvailable()``: True once a map is learned (or was loaded).

It is served by the virtual NAOqi (``naoloc serve``) and can be registered from a
naoloc process on a real NAO's session (:func:`register`, or ``python -m
naoloc.backends.naoqi.home -c nao.yaml``). :class:`HomeLocalization` is the one
adapter to naoloc's behaviours: the only place that calls ``record_survey``,
``build_from_survey``, ``localize`` and ``go_home``, so that their insides can change
behind it. Failures (no map yet, a survey that could not finish) raise one-line errors.
"""

from __future__ import annotations

import argparse
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any, Final

from naoloc.errors import NaolocError, RobotError
from naoloc.geometry import Pose2D, modulo2PI, pose2DInverse

SERVICE: Final = "NaolocLocalization"
MAP_FILE: Final = "home.npz"
DATASET_FILE: Final = "home.mcap"


class HomeLocalization:
    """The adapter from a NAOqi-style service to naoloc's behaviours.

    Args:
        robot: The robot (any backend), called on the caller's thread.
        cfg: The resolved config.
        folder: Where the home's survey and map are kept.
    """

    def __init__(self, robot: Any, cfg: Any, folder: Path) -> None:
        self._robot, self._cfg, self._folder = robot, cfg, Path(folder)
        self._map: Any = None
        self._fix: tuple[Pose2D, Pose2D] | None = None  # (map pose, odometry) at the fix
        path = self._folder / MAP_FILE
        if path.is_file():
            from naoloc.mapping import load_map

            self._map = load_map(path)

    @property
    def has_map(self) -> bool:
        """True once a home map exists."""
        return self._map is not None

    def _odometry(self) -> Pose2D:
        return Pose2D.from_list(self._robot.motion.getRobotPosition(True))

    def _need_map(self) -> Any:
        if self._map is None:
            raise RobotError("no home learned yet: call learnHome first")
        return self._map

    def learn_home(self) -> None:
        """Survey from here and build the map; this spot becomes home."""
        from naoloc.data.dataset import read_dataset
        from naoloc.data.recorder import record_survey
        from naoloc.mapping.from_survey import build_from_survey

        self._folder.mkdir(parents=True, exist_ok=True)
        dataset = self._folder / DATASET_FILE
        record_survey(self._robot, self._cfg, dataset)
        vmap, _ = build_from_survey(
            read_dataset(dataset), self._cfg.map, offset=self._cfg.survey.wall_offset_m
        )
        vmap.save(self._folder / MAP_FILE)
        self._map, self._fix = vmap, None

    def localize(self) -> bool:
        """Localize in the home map; True when the robot was found."""
        from naoloc.behaviours.localize import localize

        estimate = localize(self._robot, self._need_map(), self._cfg).estimate
        if not estimate.found:
            return False
        self._fix = (estimate.pose(), self._odometry())
        return True

    def go_home(self) -> bool:
        """Walk home; True when the last fix is within the tolerance."""
        from naoloc.behaviours.go_home import go_home

        result = go_home(self._robot, self._need_map(), self._cfg)
        if result.final.estimate.found:
            self._fix = (result.final.estimate.pose(), self._odometry())
        return bool(result.reached)

    def position(self) -> list[float]:
        """``[x, y, theta]`` in the map frame: the last fix moved by odometry since."""
        if self._fix is None:
            raise RobotError("the robot was not localized yet: call localize first")
        fix, odometry = self._fix
        now = fix * (pose2DInverse(odometry) * self._odometry())
        return [now.x, now.y, modulo2PI(now.theta)]


class LocalizationFront:
    """The NaolocLocalization service over :class:`HomeLocalization`.

    Args:
        home: The adapter.
        run: ``run(function)`` runs a behaviour where the robot may be called (the
            virtual NAOqi's robot thread; directly in a process on a real NAO).
    """

    def __init__(self, home: HomeLocalization, run: Callable[..., Any] | None = None) -> None:
        self._home = home
        self._run = run or (lambda function, *args: function(*args))
        self._busy = threading.Lock()

    def _exclusive(self, function: Callable[[], Any], what: str) -> Any:
        if not self._busy.acquire(blocking=False):
            raise RobotError(f"{what}: NaolocLocalization is busy with another call")
        try:
            return self._run(function)
        finally:
            self._busy.release()

    def learnHome(self) -> int:
        """Survey the room from here and build its map; 0 when done."""
        self._exclusive(self._home.learn_home, "learnHome")
        return 0

    def localize(self) -> int:
        """Find the robot in the home map; 0 found, 1 nothing recognised."""
        return 0 if self._exclusive(self._home.localize, "localize") else 1

    def goToHome(self) -> int:
        """Walk home; 0 when there, 1 when it stopped short."""
        return 0 if self._exclusive(self._home.go_home, "goToHome") else 1

    def getRobotPosition(self) -> list[float]:
        """``[x, y, theta]`` in the map frame (m, rad)."""
        return [float(v) for v in self._run(self._home.position)]

    def isDataAvailable(self) -> bool:
        """True once a home map exists."""
        return self._home.has_map


def register(session: Any, robot: Any, cfg: Any, folder: Path, name: str = SERVICE) -> int:
    """Serve NaolocLocalization for ``robot`` on a connected naoloc.qi ``session``.

    The service is registered with the session's robot (a NAO's directory), so any
    client of that robot can call it; it is served until the session closes.

    Returns:
        The service id.
    """
    from naoloc.backends.naoqi import qi
    from naoloc.backends.naoqi.signatures import SERVICES

    front = LocalizationFront(HomeLocalization(robot, cfg, folder))
    namespace: dict[str, Any] = {}
    for method, overloads in SERVICES[SERVICE].items():
        if hasattr(front, method):
            overload = overloads[0]
            namespace[method] = qi.bind(overload.returns, list(overload.params), method)(
                _calling(front, method)
            )
    service = type("NaolocLocalizationService", (), namespace)()
    try:
        return int(session.registerService(name, service))
    except RuntimeError as err:
        raise RobotError(f"cannot register {name}: {err}") from None


def _calling(front: LocalizationFront, method: str) -> Callable[..., Any]:
    def call(self: Any, *args: Any) -> Any:
        return getattr(front, method)(*args)

    return call


def main(argv: list[str] | None = None) -> int:
    """Register NaolocLocalization on the configured NAO and serve until Ctrl-C."""
    from naoloc.backends.naoqi import qi
    from naoloc.config import load_config
    from naoloc.robot.registry import connect

    parser = argparse.ArgumentParser(prog="python -m naoloc.backends.naoqi.home")
    parser.add_argument("-c", "--config", required=True, help="a config with robot.backend naoqi")
    parser.add_argument("--folder", default="naoloc-home", help="where the home map is kept")
    args = parser.parse_args(argv)
    try:
        cfg = load_config(args.config)
        robot = connect(cfg)
        session = qi.Session()
        session.connect(cfg.robot.url)
        register(session, robot, cfg, Path(args.folder))
    except (NaolocError, RuntimeError) as err:
        print(f"naoloc: {err}", flush=True)
        return 1
    print(f"naoloc: {SERVICE} registered at {cfg.robot.url}", flush=True)
    stop = threading.Event()
    try:
        while not stop.wait(1.0):
            if not session.isConnected():
                return 1
    except KeyboardInterrupt:
        pass
    finally:
        session.close()
        robot.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
