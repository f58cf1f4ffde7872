"""Run surveys, map builds and localizations over a process pool, one simulator per task.

Tasks are plain picklable dataclasses; every one carries its config as a dict and its
seeds explicitly, so a result does not depend on which worker ran it or in which order.
The pool uses the ``spawn`` start method (MuJoCo's renderer must be created inside each
process); with one worker everything runs in the calling process. Progress goes to a
:class:`naoloc.viz.progress.Progress` bar on stderr.

A localization chunk creates one robot from its config, optionally changes the world
(moves or removes a poster through ``robot.sim``), then for each test pose teleports the
robot there and, for each way of taking pictures (a head scan, or the paper's two
pictures of the nearest wall), runs the localize behaviour once with the first scorer of
that strategy and re-scores the very same pictures with every other (map, mode) pair, so
comparisons see exactly the same images; a re-scored scan gets the floor step with the
floor lines the localization measured there (they do not depend on the map). A world
change the simulator lacks makes the chunk's variants "skipped" (with the reason), never
silently measured without it.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import faulthandler
import math
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from naoloc.errors import (
    ConfigError,
    DependencyNotInstalled,
    MotionError,
    NaolocError,
    RobotError,
    SurveyError,
)
from naoloc.evaluation.protocols import EvalPose, room_to_map
from naoloc.geometry import Pose2D, modulo2PI
from naoloc.viz.progress import Progress

T = TypeVar("T")
R = TypeVar("R")


@dataclass(frozen=True)
class SurveyTask:
    """Survey a room and write the dataset.

    Attributes:
        name: Label of the survey (e.g. "base", "drift-x4").
        config: Resolved config as a dict (world.odometry sets the drift).
        dataset_path: Where the MCAP dataset goes.
    """

    name: str
    config: dict[str, Any]
    dataset_path: str


@dataclass(frozen=True)
class MapTask:
    """Build one map from a dataset and save it.

    Attributes:
        name: Map label (e.g. "akaze-300").
        dataset_path: The survey dataset (MCAP).
        map_config: ``map`` section of the config as a dict.
        map_path: Where the ``.npz`` map goes.
    """

    name: str
    dataset_path: str
    map_config: dict[str, Any]
    map_path: str


@dataclass(frozen=True)
class Scorer:
    """One (map, mode) pair that scores a chunk's queries.

    Attributes:
        variant: Name of the variant the estimates belong to.
        map_path: The map file.
        mode: "verified" or "paper" (the map's modes), or "nearest" for the plain
            nearest-neighbour baseline over the training images.
        strategy: How the queries are taken: "scan" (head sweep) or "paper" (nearest wall,
            two pictures). The first scorer of each strategy runs the localize behaviour;
            the others re-score its pictures.
    """

    variant: str
    map_path: str
    mode: str
    strategy: str


@dataclass(frozen=True)
class LocalizeChunk:
    """Test poses localized by one robot.

    Attributes:
        config: Config of the robot that localizes (may differ from the survey's: lighting,
            camera noise).
        origin_room_pose: True pose at the survey start (room frame): the map frame's origin.
        poses: The test poses (room frame).
        scorers: The first runs the localize behaviour; the rest re-score its queries.
        world_changes: ``(SimControl method, args)`` applied once after the robot is created,
            e.g. ``("remove_poster", ("y0",))``; a wall id as a poster method's first
            argument stands for the middle poster on that wall.
        record_dir: Where each filter localization's observations are recorded
            (``VARIANT_INDEX.mcap``, replayed by ``naoloc replay``); None: not recorded.
    """

    config: dict[str, Any]
    origin_room_pose: tuple[float, float, float]
    poses: tuple[EvalPose, ...]
    scorers: tuple[Scorer, ...]
    world_changes: tuple[tuple[str, tuple[Any, ...]], ...] = field(default_factory=tuple)
    record_dir: str | None = None


def _share_cores(threads: int) -> None:
    """A pool worker's initializer: OpenCV's thread pool at ``threads`` (the machine's
    cores over the workers), so workers do not oversubscribe the cores and each worker's
    ``compute_ms`` is not inflated by threads waiting on each other."""
    import cv2

    cv2.setNumThreads(threads)


class LocalExecutor:
    """Tasks on this machine: a ``spawn`` process pool, or the calling process for one worker."""

    name = "local"

    def run(
        self, fn: Callable[[T], R], tasks: Sequence[T], workers: int, bar: Progress, label: str
    ) -> list[R]:
        """Run ``fn`` over ``tasks``; results in the order of ``tasks``."""
        results: list[Any] = [None] * len(tasks)
        if workers <= 1 or len(tasks) <= 1:
            for i, task in enumerate(tasks):
                results[i] = fn(task)
                bar.update()
            return results
        ctx = multiprocessing.get_context("spawn")
        procs = min(workers, len(tasks))
        threads = max(1, (os.cpu_count() or 1) // procs)  # the cores shared, not oversubscribed
        with cf.ProcessPoolExecutor(
            max_workers=procs, mp_context=ctx, initializer=_share_cores, initargs=(threads,)
        ) as pool:
            futures = {pool.submit(fn, task): i for i, task in enumerate(tasks)}
            try:
                for fut in cf.as_completed(futures):
                    results[futures[fut]] = fut.result()
                    bar.update()
            except cf.process.BrokenProcessPool as err:
                raise NaolocError(f"{label}: a worker process died ({err})") from None
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
        return results

    def close(self) -> None:
        """Nothing to release."""


class RayExecutor:
    """The same tasks as Ray remote tasks, on a cluster or on a local one started here.

    Each task runs ``fn(task)`` in a Ray worker process, one CPU each; results come back
    in the order of ``tasks`` and are the same as the local pool's (tasks carry their
    configs and seeds). A local cluster advertises 127.0.0.1 and has no dashboard; Ray's
    own GCS, raylet and worker gRPC servers still listen on every interface (measured with
    Ray 2.60, which protects them with its default token authentication). On a
    remote cluster every node needs naoloc installed (``pip install 'naoloc[sim,ray]'``) and
    the outputs folder on a shared filesystem.

    ``ray.init`` installs its own SIGTERM handler and fatal-signal handlers, and
    ``ray.shutdown`` leaves SIGTERM, SIGABRT and SIGSEGV at their default action: the
    process's SIGINT/SIGTERM handlers (naoloc's clean interrupt) are put back after both, and
    :mod:`faulthandler`, if it was on, is turned on again (on ``sys.stderr``).

    Args:
        address: A running cluster (``ray://host:10001`` or ``host:6379``); None starts a
            local one with ``num_cpus``.
        num_cpus: CPUs of a local cluster (default: all).

    Raises:
        DependencyNotInstalled: Ray is not installed (``pip install 'naoloc[ray]'``).
    """

    name = "ray"

    def __init__(self, address: str | None = None, num_cpus: int | None = None) -> None:
        try:
            import ray
        except ImportError:
            raise DependencyNotInstalled(
                "--executor ray needs Ray: pip install 'naoloc[ray]'"
            ) from None
        self._ray = ray
        self._started = False
        self._handlers = _signal_handlers()
        if not ray.is_initialized():
            kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
            if address is None:
                kwargs.update(
                    num_cpus=num_cpus, _node_ip_address="127.0.0.1",
                    object_store_memory=256 * 1024 * 1024,
                )  # fmt: skip
            ray.init(address=address, **kwargs)
            self._started = True
            _restore_signal_handlers(self._handlers)

    def run(
        self, fn: Callable[[T], R], tasks: Sequence[T], workers: int, bar: Progress, label: str
    ) -> list[R]:
        """Run ``fn`` over ``tasks`` as Ray tasks; results in the order of ``tasks``."""
        ray = self._ray
        remote = ray.remote(num_cpus=1, max_retries=0)(fn)
        refs = [remote.remote(task) for task in tasks]
        index = {ref: i for i, ref in enumerate(refs)}
        results: list[Any] = [None] * len(tasks)
        pending = list(refs)
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    try:
                        results[index[ref]] = ray.get(ref)
                    except ray.exceptions.RayTaskError as err:
                        cause = err.as_instanceof_cause()
                        if isinstance(cause, NaolocError):
                            raise cause from None
                        raise NaolocError(f"{label}: a Ray task failed: {err}") from None
                    except ray.exceptions.RayError as err:
                        raise NaolocError(f"{label}: a Ray worker died ({err})") from None
                    bar.update()
        except BaseException:
            for ref in pending:
                ray.cancel(ref)
            raise
        return results

    def close(self) -> None:
        """Shut down the local cluster this executor started (a joined one stays up)."""
        if self._started:
            self._started = False
            self._ray.shutdown()
            _restore_signal_handlers(self._handlers)


_SignalHandlers = tuple[dict[int, Any], bool]


def _signal_handlers() -> _SignalHandlers:
    """This process's Python SIGINT/SIGTERM handlers and whether faulthandler is on."""
    handlers = {int(s): signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    return handlers, faulthandler.is_enabled()


def _restore_signal_handlers(saved: _SignalHandlers) -> None:
    """Put back what :func:`_signal_handlers` saw (Python sets handlers in the main thread only)."""
    handlers, fault = saved
    if threading.current_thread() is not threading.main_thread():
        return
    for signum, handler in handlers.items():
        if handler is not None:  # None: set outside Python, nothing to put back
            signal.signal(signum, handler)
    if fault:
        faulthandler.disable()  # enable() does nothing while it believes it is still on
        with contextlib.suppress(RuntimeError, OSError, ValueError, AttributeError):
            faulthandler.enable(file=sys.stderr)  # a stderr without a file descriptor: off


Executor = LocalExecutor | RayExecutor


def make_executor(name: str, address: str | None = None, workers: int | None = None) -> Executor:
    """The executor of ``--executor NAME [--ray-address ADDR]``.

    Raises:
        ConfigError: An unknown name, or an address without ``ray``.
        DependencyNotInstalled: ``ray`` without Ray installed.
    """
    if name == "local":
        if address is not None:
            raise ConfigError("--ray-address needs --executor ray")
        return LocalExecutor()
    if name == "ray":
        return RayExecutor(address, num_cpus=workers)
    raise ConfigError(f"unknown executor {name!r}; valid: local, ray")


def run_tasks(
    fn: Callable[[T], R],
    tasks: Sequence[T],
    workers: int,
    label: str,
    *,
    progress: bool | None = None,
    executor: Executor | None = None,
) -> list[R]:
    """Run ``fn`` over ``tasks`` on ``executor`` (default: a local spawn process pool).

    Args:
        fn: A module-level function (picklable).
        tasks: Picklable task objects.
        workers: Processes of the local pool; 1 runs in the calling process.
        label: Progress bar label.
        progress: Force the bar on or off; default: on when stderr is a terminal.
        executor: Where the tasks run: :class:`LocalExecutor` (default) or
            :class:`RayExecutor`; the results are the same.

    Returns:
        Results in the order of ``tasks``.
    """
    runner = executor if executor is not None else LocalExecutor()
    with Progress(len(tasks), label, enabled=progress) as bar:
        return runner.run(fn, tasks, workers, bar, label)


def chunked(items: Sequence[T], size: int) -> list[tuple[T, ...]]:
    """Split ``items`` into consecutive tuples of at most ``size`` (>= 1) items."""
    size = max(1, size)
    return [tuple(items[i : i + size]) for i in range(0, len(items), size)]


def survey_task(task: SurveyTask) -> dict[str, Any]:
    """Survey a room with the survey behaviour and write the dataset (runs in a worker).

    Returns:
        ``{"name", "dataset", "frames", "laps", "path_m", "wall_s", "meta"}``, plus
        ``"failed"`` (the reason) when a step failed.
    """
    from naoloc.data.recorder import record_survey
    from naoloc.robot.registry import connect

    path = Path(task.dataset_path)
    t0 = time.monotonic()
    with connect(task.config) as robot:
        _require_sim(robot)
        try:
            result, frames = record_survey(robot, _config(task.config), path)
        except (MotionError, SurveyError) as err:  # walked into furniture; no wall to follow
            return {"name": task.name, "dataset": str(path), "frames": 0, "laps": 0,
                    "path_m": 0.0, "wall_s": time.monotonic() - t0, "meta": {},
                    "failed": str(err)}  # fmt: skip
    return {
        "name": task.name,
        "dataset": str(path),
        "frames": frames,
        "laps": result.laps,
        "path_m": result.path_m,
        "wall_s": result.wall_s,
        "meta": result.meta,
    }


def map_task(task: MapTask) -> dict[str, Any]:
    """Build a map from a dataset and save it (runs in a worker).

    Returns:
        ``{"name", "map", "images", "far_images", "neurons", "epochs", "features",
        "distinct_poses", "timings"}`` (``images``: the wall pictures the GCS learned).
    """
    from naoloc.config import MapConfig
    from naoloc.data.dataset import read_dataset
    from naoloc.mapping.from_survey import build_from_survey

    data = read_dataset(task.dataset_path)
    cfg = MapConfig.model_validate(task.map_config)
    vmap, _ = build_from_survey(data, cfg)  # as naoloc build-map does
    Path(task.map_path).parent.mkdir(parents=True, exist_ok=True)
    vmap.save(task.map_path)
    return {
        "name": task.name,
        "map": task.map_path,
        "images": int(vmap.wall_images),  # the GCS's training images (Table 2)
        "far_images": int(vmap.far_images),
        "neurons": cfg.neurons,
        "epochs": cfg.epochs,
        "features": cfg.features,
        "distinct_poses": int(vmap.distinct_poses),
        "timings": {k: float(v) for k, v in vmap.timings.items()},
    }


def localize_chunk(chunk: LocalizeChunk) -> list[dict[str, Any]]:
    """Localize the robot at each test pose of a chunk (runs in a worker).

    Returns:
        One record per (pose, scorer): ``variant, index, group, seed, room_pose, truth,
        estimate, confidence, error_m, heading_error_deg, localize_ms, compute_ms, details``
        (map frame; ``localize_ms`` wall time of pictures and map, ``compute_ms`` CPU time of
        the map's work alone).
    """
    from naoloc.mapping import load_map
    from naoloc.robot.registry import connect

    cfg = _config(chunk.config)
    records: list[dict[str, Any]] = []
    with connect(cfg) as robot:
        sim = _require_sim(robot)
        for method, args in chunk.world_changes:
            change = getattr(sim, method, None)
            if change is None:  # reported as skipped, not silently measured without the change
                reason = f"the {robot.backend} simulator has no {method}()"
                return [{"variant": s.variant, "skipped": reason} for s in chunk.scorers]
            change(*_resolve_posters(sim, method, args))
        maps = {s.map_path: load_map(s.map_path) for s in chunk.scorers}
        for pose in chunk.poses:
            taken: dict[str, tuple[Any, Pose2D, Any]] = {}  # localization, truth, its map
            done: dict[tuple[str, str, str], tuple[Any, float, float]] = {}
            for scorer in chunk.scorers:
                key = (scorer.map_path, scorer.mode, scorer.strategy)
                if key in done:
                    est, ms, cpu = done[key]
                elif scorer.strategy not in taken:
                    try:
                        sim.teleport(*pose.room_pose)
                    except RobotError as err:  # furniture there: not the localizer's fault
                        records.append({"variant": scorer.variant, "skipped": str(err)})
                        break
                    vmap = maps[scorer.map_path]
                    est, result, ms, cpu = _localize_recorded(
                        robot, vmap, cfg, scorer, _recording_path(chunk, scorer, pose)
                    )
                    truth = room_to_map(chunk.origin_room_pose, sim.true_pose())
                    taken[scorer.strategy] = (result, truth, vmap)
                else:
                    t1, c1 = time.perf_counter(), time.process_time()
                    result, _, first = taken[scorer.strategy]
                    est = _rescore(maps[scorer.map_path], first, result, scorer.mode, cfg)
                    ms = (time.perf_counter() - t1) * 1e3
                    cpu = (time.process_time() - c1) * 1e3
                done[key] = (est, ms, cpu)
                result, truth, _ = taken[scorer.strategy]
                records.append(_record(scorer, pose, truth, est, (ms, cpu), result))
    return records


def _record(
    scorer: Scorer,
    pose: EvalPose,
    truth: Pose2D,
    est: Any,
    times_ms: tuple[float, float],
    result: Any,
) -> dict[str, Any]:
    ex, ey, et = float(est.x), float(est.y), float(est.theta)
    err = math.hypot(ex - truth.x, ey - truth.y)
    head = abs(modulo2PI(et - truth.theta)) if math.isfinite(et) else float("nan")
    details = dict(getattr(est, "evidence", {}) or {})
    details["queries"] = result.pictures
    details["line_scans"] = result.line_scans
    details["extra_turns"] = result.extra_turns
    if est.reason:
        details["reason"] = est.reason
    cov = est.covariance
    return {
        "variant": scorer.variant,
        "mode": scorer.mode,
        "index": pose.index,
        "group": pose.group,
        "seed": pose.seed,
        "room_pose": list(pose.room_pose),
        "truth": truth.to_list(),
        "estimate": [ex, ey, et],
        "confidence": float(est.confidence),
        "status": str(est.status),
        "covariance": None if cov is None else np.asarray(cov).tolist(),
        "error_m": err if math.isfinite(err) else float("nan"),
        "heading_error_deg": math.degrees(head),
        "localize_ms": times_ms[0],
        "compute_ms": times_ms[1],
        "robot_s": float(result.robot_s),
        "details": jsonable(details),
    }


def jsonable(value: Any) -> Any:
    """``value`` with numpy types as Python ones and NaN/inf as None (strict JSON)."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _resolve_posters(sim: Any, method: str, args: tuple[Any, ...]) -> tuple[Any, ...]:
    """For poster changes, turn a wall id ("x0", "x1", "y0", "y1") into its middle poster.

    Raises:
        RobotError: The wall has no poster.
    """
    if not method.endswith("_poster") or not args or args[0] not in ("x0", "x1", "y0", "y1"):
        return args
    names = sorted(n for n in sim.poster_names() if n.startswith(f"poster_{args[0]}_"))
    if not names:
        raise RobotError(f"wall {args[0]} has no poster to change")
    return (names[len(names) // 2], *args[1:])


def _config(data: dict[str, Any]) -> Any:
    from naoloc.config import load_config

    return load_config(data)


def _require_sim(robot: Any) -> Any:
    if robot.sim is None:
        raise NaolocError(f"evaluate needs a simulator (robot.sim); the {robot.backend} has none")
    return robot.sim


def _recording_path(chunk: LocalizeChunk, scorer: Scorer, pose: EvalPose) -> Path | None:
    """Where a test pose's localization is recorded: only with ``chunk.record_dir``, and only
    a filter's (the paper's mode and strategy do not use it)."""
    paper = scorer.mode in ("paper", "nearest") or scorer.strategy == "paper"
    if chunk.record_dir is None or paper:
        return None
    return Path(chunk.record_dir) / f"{scorer.variant.replace('/', '_')}_{pose.index:03d}.mcap"


def _localize_recorded(
    robot: Any, vmap: Any, cfg: Any, scorer: Scorer, path: Path | None
) -> tuple[Any, Any, float, float]:
    """:func:`_localize`, its filter's every observation written to ``path`` (None: not
    recorded); a localization that fails keeps ``NAME.partial.mcap``."""
    if path is None:
        return _localize(robot, vmap, cfg, scorer)
    from naoloc.data.recording import recorded_localizer

    path.parent.mkdir(parents=True, exist_ok=True)
    with recorded_localizer(path, cfg, "localize", Path(scorer.map_path), vmap) as loc:
        return _localize(robot, vmap, cfg, scorer, loc)


def _localize(
    robot: Any, vmap: Any, cfg: Any, scorer: Scorer, localizer: Any = None
) -> tuple[Any, Any, float, float]:
    """Run the localize behaviour (with ``localizer``'s filter when given); returns the
    estimate, the localization, its wall time (ms) and the CPU time of its estimation (ms)."""
    from naoloc.behaviours.localize import localize
    from naoloc.localization.paper import localize_nearest_image

    mode = "paper" if scorer.mode == "nearest" else scorer.mode
    result = localize(robot, vmap, cfg, mode=mode, strategy=scorer.strategy, localizer=localizer)
    if scorer.mode == "nearest":
        c1 = time.process_time()
        est = localize_nearest_image(vmap, result.queries)
        return est, result, float(result.wall_s) * 1e3, (time.process_time() - c1) * 1e3
    return result.estimate, result, float(result.wall_s) * 1e3, float(result.compute_s) * 1e3


def _rescore(vmap: Any, first: Any, result: Any, mode: str, cfg: Any) -> Any:
    """The estimate another map (or mode) gives from a localization's observations.

    The scan strategy's observations are replayed through a filter over ``vmap`` (as hloc
    re-runs from stored features: the same pictures and lines, matched to this map); the
    paper's pictures go to Algorithm 5 or the nearest image.
    """
    from naoloc.localization.localizer import replay
    from naoloc.localization.paper import localize_nearest_image, localize_paper

    queries = result.queries
    if mode == "nearest":
        return localize_nearest_image(vmap, queries)
    if mode == "paper" or result.strategy == "paper":
        return localize_paper(vmap, vmap.extract(queries), queries)
    same = vmap.feature_params == first.feature_params
    return replay(vmap, result.observations, cfg.localize.filter, same_features=same).pose()
