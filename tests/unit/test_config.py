"""Config: defaults, shipped files, and one-line errors that name the key path."""

from __future__ import annotations

from pathlib import Path

import pytest

from naoloc.config import Config, FloorLineTuning, load_config
from naoloc.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]


def test_defaults_match_the_contract() -> None:
    cfg = load_config(None)
    assert cfg.robot.backend == "mujoco"
    assert cfg.robot.url == "tcp://127.0.0.1:9559"
    assert cfg.world.room.size_m == (6.0, 6.0)
    assert cfg.camera.resolution == 1 and cfg.camera.colorspace == 11
    assert (cfg.survey.laps, cfg.survey.step_m, cfg.survey.wall_offset_m) == (2, 0.2, 1.0)
    assert (cfg.map.features, cfg.map.neurons, cfg.map.epochs) == ("akaze", 300, 300)
    assert cfg.start_pose() == (1.0, 1.0, 0.0)
    assert cfg.survey_sides() == (4.0, 4.0)


@pytest.mark.parametrize("path", sorted((ROOT / "configs").glob("*.yaml")), ids=lambda p: p.name)
def test_shipped_configs_validate(path: Path) -> None:
    cfg = load_config(path)
    assert isinstance(cfg, Config)


def test_minimal_file_is_complete(tmp_path: Path) -> None:
    f = tmp_path / "room.yaml"
    f.write_text("world:\n  room:\n    size_m: [5.0, 4.0]\n    seed: 7\n")
    cfg = load_config(f)
    assert cfg.survey_sides() == (3.0, 2.0)
    assert cfg.world.room.seed == 7


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("world:\n  room:\n    sise_m: [5, 5]\n", "world.room.sise_m: unknown key"),
        ("robot:\n  backend: webots\n", "robot.backend"),
        ("camera: {resolution: 99}\n", "camera.resolution"),
        ("survey: {laps: 0}\n", "survey.laps"),
        ("survey: {wall_offset_m: 3.5}\n", "survey.wall_offset_m"),
        ("world: {start_pose: [9, 1, 0]}\n", "world.start_pose"),
        ("camera: {floor_lines: {ghost_ratio: [1.5, 1.2]}}\n", "camera.floor_lines.ghost_ratio"),
        ("camera: {floor_lines: {min_span: 0.3}}\n", "camera.floor_lines.min_span: unknown key"),
        ("- just\n- a list\n", "top level must be a mapping"),
        ("robot: [\n", "line"),
    ],
)
def test_errors_are_one_line_with_file_and_key(tmp_path: Path, text: str, fragment: str) -> None:
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_config(f)
    msg = str(info.value)
    assert "\n" not in msg
    assert msg.startswith(str(f))
    assert fragment in msg


def test_floor_line_tuning_defaults_are_the_detectors_and_bad_ranges_name_the_key() -> None:
    tun = load_config(None).camera.floor_lines
    assert tun == FloorLineTuning()
    assert (tun.min_inliers, tun.min_span_m, tun.max_range_m) == (12, 0.3, 4.0)
    assert (tun.tone_ratio, tun.chroma_tol, tun.ghost_ratio) == (
        (0.75, 1.45),
        (0.008, 0.02),
        (1.04, 1.4),
    )
    with pytest.raises(ConfigError, match=r"camera\.floor_lines\.ghost_ratio: .*low < high"):
        load_config({"camera": {"floor_lines": {"ghost_ratio": [1.5, 1.2]}}})
    with pytest.raises(ConfigError, match=r"camera\.floor_lines\.chroma_tol"):
        load_config({"camera": {"floor_lines": {"chroma_tol": [0.03, 0.01]}}})
    with pytest.raises(ConfigError, match=r"camera\.floor_lines\.ransac_sample: unknown key"):
        load_config({"camera": {"floor_lines": {"ransac_sample": 100}}})
    tuned = load_config({"camera": {"floor_lines": {"min_span_m": 0.5}}})
    assert tuned.camera.floor_lines.min_span_m == 0.5 and tuned.camera.floor_lines.min_inliers == 12


def test_missing_file() -> None:
    with pytest.raises(ConfigError, match="no such config file"):
        load_config("/nonexistent/naoloc.yaml")


def test_yaml_is_loaded_safely(tmp_path: Path) -> None:
    f = tmp_path / "evil.yaml"
    f.write_text("robot: !!python/object/apply:os.system ['echo pwned']\n")
    with pytest.raises(ConfigError):
        load_config(f)


def test_config_is_immutable_and_overridable() -> None:
    cfg = load_config({"robot": {"backend": "fake"}})
    with pytest.raises(Exception):  # noqa: B017 - pydantic's frozen error
        cfg.robot.backend = "mujoco"  # type: ignore[misc]
    other = cfg.with_overrides({"map": {"neurons": 100}})
    assert other.map.neurons == 100 and cfg.map.neurons == 300
    assert load_config(other.to_dict()) == other


def test_a_retired_key_is_dropped_with_a_warning_and_the_source_is_untouched(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Configs saved with earlier datasets and recordings name keys a release retired."""
    walls = {"start_gate_rad": 0.06, "edge_m": 0.12}
    data = {"map": {"tuning": {"wall_poses": walls}}}
    with caplog.at_level("WARNING", logger="naoloc.config"):
        cfg = load_config(data)
    assert cfg.map.tuning.wall_poses.edge_m == 0.12
    assert "start_gate_rad is retired" in caplog.text
    assert walls == {"start_gate_rad": 0.06, "edge_m": 0.12}
    with pytest.raises(ConfigError, match="unknown key"):
        load_config({"map": {"tuning": {"wall_poses": {"start_gate": 0.06}}}})
