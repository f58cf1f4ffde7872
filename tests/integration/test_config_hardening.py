"""Config files an attacker or an unlucky user writes: every one is a one-line ConfigError.

Each message names the file, the key path (or line) and the problem; nothing hangs,
recurses or inflates (YAML alias bombs, deep nesting, huge integers, NaN and inf).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from naoloc.config import MAX_CONFIG_BYTES, load_config
from naoloc.errors import ConfigError


def _laughs(levels: int = 9, where: str = "world:\n  room:\n    size_m: *l{last}\n") -> str:
    lines = ['l0: &l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for n in range(1, levels):
        lines.append(f"l{n}: &l{n} [" + ", ".join([f"*l{n - 1}"] * 9) + "]")
    return "\n".join(lines) + "\n" + where.format(last=levels - 1)


def _typed_laughs(levels: int = 9) -> str:
    """The bomb's anchors inside a typed key, so the bomb is what pydantic would validate."""
    text = "world:\n  room:\n    size_m:\n"
    text += '      - &l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]\n'
    for n in range(1, levels):
        text += f"      - &l{n} [" + ", ".join([f"*l{n - 1}"] * 9) + "]\n"
    return text


BAD = {
    "digits_seed": ("map: {seed: " + "9" * 5000 + "}\n", ["map.seed", "digits"]),
    "digits_negative": ("world: {room: {seed: -" + "1" * 300 + "}}\n", ["world.room.seed"]),
    "int64_overflow": ("map: {seed: 99999999999999999999}\n", ["map.seed"]),
    "deep_flow": ("map: " + "[" * 5000 + "]" * 5000 + "\n", ["nested deeper"]),
    "deep_block": (
        "".join("  " * i + f"k{i}:\n" for i in range(300)) + "  " * 300 + "x: 1\n",
        ["nested deeper"],
    ),
    "laughs_key": (_laughs(), ["alias", "expand"]),
    "laughs_typed": (_typed_laughs(), ["alias", "expand"]),
    "recursive_alias": ("survey: &a {side_m: *a}\n", ["recursive"]),
    "nan_step": ("survey: {step_m: .nan}\n", ["survey.step_m", "finite"]),
    "inf_timeout": ("robot: {timeout_s: .inf}\n", ["robot.timeout_s", "finite"]),
    "nan_pose": ("world: {start_pose: [.nan, 1.0, 0.0]}\n", ["world.start_pose.0", "finite"]),
    "inf_theta": ("world: {start_pose: [1.0, 1.0, -.inf]}\n", ["world.start_pose.2", "finite"]),
    "nan_size": ("world: {room: {size_m: [.NaN, 5.0]}}\n", ["world.room.size_m.0", "finite"]),
    "nan_string": ("survey: {step_m: 'nan'}\n", ["survey.step_m", "finite"]),
    "inf_string": ("world: {room: {wall_height_m: '-inf'}}\n", ["world.room.wall_height_m"]),
    "float_overflow": ("survey: {head_yaw_rad: 1e999}\n", ["survey.head_yaw_rad", "finite"]),
    "nan_unknown_key": ("extra: {x: .nan}\n", ["extra"]),
    "yaw_range": ("survey: {head_yaw_rad: 7.0}\n", ["survey.head_yaw_rad"]),
    "timeout_range": ("robot: {timeout_s: 1e12}\n", ["robot.timeout_s"]),
    "bad_date": ("map: {seed: 2001-02-30}\n", ["map.seed"]),
    "huge_string": ("robot: {url: '" + "a" * 20000 + "'}\n", ["robot.url", "long"]),
    "nul_bytes": ("robot:\x00 {backend: fake}\n", ["bad.yaml"]),
    "tabs": ("robot:\n\t backend: fake\n", ["line"]),
    "list_key": ("? [1, 2]\n: 3\n", ["bad.yaml"]),
    "python_tag": ("robot: !!python/name:os.system\n", ["bad.yaml"]),
    "binary_tag": ("robot: {url: !!binary 'not base64!'}\n", ["bad.yaml"]),
    "too_many_nodes": ("map: [" + ", ".join(["1"] * 30000) + "]\n", ["values"]),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_configs_are_one_line_errors(tmp_path: Path, name: str) -> None:
    text, fragments = BAD[name]
    path = tmp_path / "bad.yaml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    message = str(info.value)
    assert "\n" not in message and len(message) < 400, message[:1000]
    assert message.startswith(str(path)), message
    for fragment in fragments:
        assert fragment in message, message


def test_a_file_over_the_size_cap_is_refused_without_reading_it_all(tmp_path: Path) -> None:
    path = tmp_path / "big.yaml"
    path.write_text("# padding\n" * (MAX_CONFIG_BYTES // 10 + 10))
    with pytest.raises(ConfigError, match="too large"):
        load_config(path)


def test_dev_zero_is_refused_quickly() -> None:
    with pytest.raises(ConfigError, match="is a character device, not a config file"):
        load_config("/dev/zero")


def test_a_folder_is_a_one_line_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as info:
        load_config(tmp_path)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "data",
    [
        {"survey": {"step_m": float("nan")}},
        {"world": {"start_pose": [1.0, float("inf"), 0.0]}},
        {"map": {"seed": 10**5000}},
    ],
)
def test_dict_sources_are_checked_too(data: dict[str, object]) -> None:
    with pytest.raises(ConfigError) as info:
        load_config(data)
    assert "\n" not in str(info.value) and len(str(info.value)) < 400


def test_deeply_nested_dicts_are_refused() -> None:
    deep: dict[str, object] = {}
    node = deep
    for _ in range(5000):
        node["x"] = {}
        node = node["x"]  # type: ignore[assignment]
    with pytest.raises(ConfigError, match="nested deeper"):
        load_config({"world": deep})


def test_aliases_within_the_limits_still_work(tmp_path: Path) -> None:
    path = tmp_path / "ok.yaml"
    path.write_text(
        "world:\n  room:\n    size_m: &s [5.0, 4.0]\nsurvey:\n  side_m: *s\n  wall_offset_m: 0.5\n"
    )
    cfg = load_config(path)
    assert cfg.survey.side_m == (5.0, 4.0)


def test_error_messages_never_repr_a_huge_input(tmp_path: Path) -> None:
    path = tmp_path / "big_list.yaml"
    path.write_text("world: {room: {size_m: [" + ", ".join(["1.0"] * 5000) + "]}}\n")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert len(str(info.value)) < 300 and "world.room.size_m" in str(info.value)
