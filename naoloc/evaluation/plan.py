"""What an evaluation runs: surveys, maps and scorers for a protocol and its studies.

Studies (all on the same survey data unless said otherwise):

- ``main``: the config's map and localize mode (the JSON line's figures).
- ``compare``: paper vs verified mode; the GCS map vs plain nearest neighbour over the
  training images (both with the paper's two pictures); A-KAZE vs ORB vs SIFT;
  100/200/300 neurons (epochs = neurons) in both modes.
- ``robustness``: odometry drift during the survey (new surveys and maps); a lighting
  change, camera noise, a poster moved or removed after mapping (new robots at
  localization time).

Map names are ``<features>-<neurons>`` (plus ``-e<epochs>`` when epochs differ from
neurons) and, for drift surveys, a ``drift-x<k>/`` prefix.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from naoloc.config import Config, MapConfig

#: Odometry drift multipliers of the robustness study (x1 = the config's own drift).
DRIFT_LEVELS: tuple[float, ...] = (0.0, 1.0, 2.0, 4.0)

#: Room light scales of the robustness study (1 = as mapped).
LIGHT_LEVELS: tuple[float, ...] = (0.5, 2.0)

#: Camera degradations of the robustness study: name -> world.camera_realism overrides.
CAMERA_LEVELS: dict[str, dict[str, Any]] = {
    "noise-8": {"noise_std": 8.0},
    "noise-16-blur-1": {"noise_std": 16.0, "blur_px": 1.0, "jpeg_quality": 60},
}

#: World changes after mapping: name -> (SimControl method, args, description).
POSTER_CHANGES: dict[str, tuple[str, tuple[Any, ...], str]] = {
    "poster-moved": ("move_poster", ("y0", 1.0), "middle poster of wall 1 slid 1 m along it"),
    "poster-removed": ("remove_poster", ("y0",), "middle poster of wall 1 taken off"),
}

STUDIES = ("main", "compare", "robustness")


@dataclass(frozen=True)
class VariantSpec:
    """One named way of localizing whose errors are summarized together.

    Attributes:
        name: Unique name (a table row).
        study: "main", "paper", "compare" or "robustness".
        description: One line for the report.
        map_name: Map used.
        mode: "verified", "paper" or "nearest".
        strategy: "scan" or "paper" (how the pictures are taken).
        robot: Name of the robot set-up localizing ("base" = as surveyed).
    """

    name: str
    study: str
    description: str
    map_name: str
    mode: str
    strategy: str
    robot: str = "base"


@dataclass(frozen=True)
class RobotSpec:
    """A robot set-up at localization time.

    Attributes:
        name: "base" or a robustness level name.
        overrides: Config overrides (nested dict) on the survey config.
        world_changes: ``(SimControl method, args)`` applied after creating the robot.
        description: One line for the report.
    """

    name: str
    overrides: dict[str, Any] = field(default_factory=dict)
    world_changes: tuple[tuple[str, tuple[Any, ...]], ...] = ()
    description: str = "as surveyed"


@dataclass
class Plan:
    """Everything an evaluation runs.

    Attributes:
        surveys: Survey name -> config overrides ("base" has none).
        maps: Map name -> (survey name, map config).
        variants: Variants in report order; the first is the main one.
        robots: Robot set-ups by name.
    """

    surveys: dict[str, dict[str, Any]]
    maps: dict[str, tuple[str, MapConfig]]
    variants: list[VariantSpec]
    robots: dict[str, RobotSpec]

    @property
    def main(self) -> VariantSpec:
        """The variant the JSON line reports."""
        return self.variants[0]


def map_name(cfg: MapConfig) -> str:
    """``<features>-<neurons>`` plus ``-e<epochs>`` when epochs != neurons."""
    name = f"{cfg.features}-{cfg.neurons}"
    return name if cfg.epochs == cfg.neurons else f"{name}-e{cfg.epochs}"


def _strategy(mode: str) -> str:
    return "scan" if mode == "verified" else "paper"


def drift_overrides(cfg: Config, level: float) -> dict[str, Any]:
    """``world.odometry`` overrides that scale the config's drift by ``level``."""
    return {"world": {"odometry": {"level": cfg.world.odometry.level * level}}}


def make_plan(cfg: Config, protocol: str, studies: tuple[str, ...]) -> Plan:
    """The surveys, maps and variants of a protocol with the chosen studies.

    Args:
        cfg: The resolved config (the survey's and main map's settings).
        protocol: "paper" or "random".
        studies: Any of :data:`STUDIES`; "main" is always included.

    Returns:
        The plan; its first variant is the main one.
    """
    mode = cfg.localize.mode
    base = cfg.map
    main_map = map_name(base)
    plan = Plan({"base": {}}, {main_map: ("base", base)}, [], {"base": RobotSpec("base")})

    def add_map(mc: MapConfig, survey: str = "base") -> str:
        name = map_name(mc) if survey == "base" else f"{survey}/{map_name(mc)}"
        plan.maps.setdefault(name, (survey, mc))
        return name

    plan.variants.append(
        VariantSpec(
            "main", "main", f"default: {mode} mode, {main_map} map", main_map, mode, _strategy(mode)
        )
    )
    if protocol == "paper":
        for i, n in enumerate((100, 200, 300), start=1):
            name = add_map(base.model_copy(update={"neurons": n, "epochs": n}))
            for m in ("paper", "verified"):
                plan.variants.append(
                    VariantSpec(
                        f"map{i}-{m}", "paper", f"Table 2 map {i} ({n} neurons, {n} epochs), "
                        f"{m} mode", name, m, _strategy(m),
                    )
                )  # fmt: skip
    if "compare" in studies:
        other = "paper" if mode == "verified" else "verified"
        plan.variants.append(
            VariantSpec(
                f"{other}-mode", "compare", f"{other} mode, same map", main_map, other,
                _strategy(other),
            )
        )  # fmt: skip
        paper_name = "main" if mode == "paper" else f"{other}-mode"
        plan.variants.append(
            VariantSpec(
                "nearest-image", "compare",
                f"plain nearest neighbour over the training images (vs GCS: {paper_name})",
                main_map, "nearest", "paper",
            )
        )  # fmt: skip
        for feat in ("akaze", "orb", "sift"):
            name = add_map(base.model_copy(update={"features": feat}))
            plan.variants.append(
                VariantSpec(f"features-{feat}", "compare", f"{feat} features, {mode} mode",
                            name, mode, _strategy(mode))
            )  # fmt: skip
        for n in (100, 200, 300):
            name = add_map(base.model_copy(update={"neurons": n, "epochs": n}))
            for m in ("paper", "verified"):
                plan.variants.append(
                    VariantSpec(f"neurons-{n}-{m}", "compare", f"{n} neurons/epochs, {m} mode",
                                name, m, _strategy(m))
                )  # fmt: skip
    if "robustness" in studies:
        for level in DRIFT_LEVELS:
            survey = "base" if level == 1.0 else f"drift-x{level:g}"
            if survey != "base":
                plan.surveys[survey] = drift_overrides(cfg, level)
            name = add_map(base, survey)
            plan.variants.append(
                VariantSpec(f"drift-x{level:g}", "robustness",
                            f"survey odometry drift x{level:g} of the config's", name, mode,
                            _strategy(mode))
            )  # fmt: skip
        for light in LIGHT_LEVELS:
            rname = f"light-{light:g}"
            plan.robots[rname] = RobotSpec(
                rname, {"world": {"sim": {"light": light}}}, (), f"room light x{light:g}"
            )
        for cam_name, cam in CAMERA_LEVELS.items():
            desc = ", ".join(f"{k} {v}" for k, v in cam.items())
            plan.robots[cam_name] = RobotSpec(
                cam_name, {"world": {"camera_realism": cam}}, (), f"camera {desc}"
            )
        for change, (method, args, desc) in POSTER_CHANGES.items():
            plan.robots[change] = RobotSpec(change, {}, ((method, args),), desc)
        for spec in plan.robots.values():
            if spec.name == "base":
                continue
            plan.variants.append(
                VariantSpec(spec.name, "robustness", f"{spec.description} at localization",
                            main_map, mode, _strategy(mode), spec.name)
            )  # fmt: skip
    return plan
