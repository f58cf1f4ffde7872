"""go-home in the MuJoCo paper room: from behind a chair it walks around it and arrives."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml

from naoloc.app.cli import main
from naoloc.config import load_config

pytest.importorskip("mujoco")
pytestmark = [pytest.mark.sim, pytest.mark.slow]

CONFIG = Path(__file__).resolve().parents[2] / "configs" / "sim_paper_room.yaml"


def _behind_a_chair() -> tuple[float, float, float]:
    """A start (room frame) 0.75 m beyond a chair from the map origin, facing away from home."""
    from naoloc.backends.mujoco.room import build_layout

    cfg = load_config(CONFIG).with_overrides({"world": {"room": {"style": "posters"}}})
    layout = build_layout(cfg)
    ox, oy, _ = cfg.start_pose()
    for chair in (f for f in layout.furniture if f.kind == "chair"):
        cx, cy = (chair.rect[0] + chair.rect[2]) / 2, (chair.rect[1] + chair.rect[3]) / 2
        d = math.hypot(cx - ox, cy - oy)
        ux, uy = (cx - ox) / d, (cy - oy) / d
        x, y = cx + 0.75 * ux, cy + 0.75 * uy
        if layout.is_free(x, y, 0.3):
            return x, y, math.atan2(uy, ux)
    pytest.skip("no chair of the paper room has free floor behind it")


def test_go_home_walks_around_a_chair(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    at = _behind_a_chair()
    # The map from a survey on exact odometry (this test is about the walk home, not the
    # survey); the walk home on a NAO's drifting, open-loop odometry (the default).
    ideal = tmp_path / "ideal.yaml"
    # Posters in the camera's band: the map must see well for this test of the walk home
    # (seeing art at real heights is tested elsewhere).
    posters = {"room": {"style": "posters"}}
    exact = load_config(CONFIG).with_overrides(
        {
            "world": {
                **posters,
                "odometry": {"profile": "ideal"},
                "camera_realism": {"profile": "ideal"},
            }
        }
    )
    ideal.write_text(yaml.safe_dump(exact.to_dict()))
    honest = tmp_path / "honest.yaml"
    honest.write_text(
        yaml.safe_dump(load_config(CONFIG).with_overrides({"world": posters}).to_dict())
    )
    assert main(["survey", "-c", str(ideal), "-o", str(tmp_path / "s.mcap")]) == 0
    assert main(["build-map", "-c", str(ideal), "-d", str(tmp_path / "s.mcap"),
                 "-o", str(tmp_path / "m.npz")]) == 0  # fmt: skip
    capsys.readouterr()
    png = tmp_path / "home.png"
    args = ["go-home", "-c", str(honest), "-m", str(tmp_path / "m.npz"), "--png", str(png)]
    assert main([*args, "--at", *(f"{v:.4f}" for v in at)]) == 0
    line = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert line["reached"] is True, line
    assert line["error_m"] < 0.3
    # The straight line home runs through the chair: the walk is longer than that line.
    assert line["path_m"] > 1.05 * math.hypot(line["start"][0], line["start"][1])
    assert png.is_file() and png.stat().st_size > 10_000
    if line["tries"] != 1:  # it should walk home on the live pose without stopping to look
        pytest.xfail(
            f"the belief was lost {line['tries'] - 1} times on the way (walking pictures of "
            "this posters room give little evidence that it is the mapped room: issue 30)"
        )
