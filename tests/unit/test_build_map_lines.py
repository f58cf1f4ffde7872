"""What ``naoloc build-map`` prints about the survey's walls, beside the checks."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import pytest

from naoloc.app.commands import build_map
from naoloc.config import load_config


def _summary(hidden: list[list[float]]) -> dict[str, Any]:
    return {
        "images": 40, "neurons": 30, "distinct_poses": 20, "total_s": 1.0, "png": "m.png",
        "dataset_complete": True, "checked": True, "checks": [],
        "wall_poses": {"hidden": hidden, "faces": []},
    }  # fmt: skip


@pytest.mark.parametrize(
    ("hidden", "lines"),
    [
        ([], []),
        (
            [[1, 0.2797], [5, 0.2797], [9, 0.2797]],
            [
                "side 2 followed a front 0.28 m before its wall all along (a wardrobe, a bed; "
                "lap 1, 2, 3)"
            ],
        ),
        (
            [[2, 0.42], [7, 0.3]],
            ["side 3 followed a front 0.42 m", "side 4 followed a front 0.30 m"],
        ),
    ],
)
def test_build_map_names_the_sides_that_followed_a_front_hiding_their_wall(
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
    hidden: list[list[float]],
    lines: list[str],
) -> None:
    monkeypatch.setattr(build_map, "build_from_dataset", lambda *a, **k: (None, _summary(hidden)))
    args = argparse.Namespace(dataset=tmp_path / "s.mcap", output=tmp_path / "m.npz")
    build_map.run(args, load_config({"robot": {"backend": "fake"}}))
    said = [ln for ln in capsys.readouterr().out.splitlines() if "followed a front" in ln]
    assert len(said) == len(lines)
    for line, expected in zip(said, lines, strict=True):
        assert expected in line and line.endswith("the sides toward it end that much early")
