"""Issue 33, item 2: ``--record`` on localize, track and go-home, and ``naoloc replay``.

A recorded localization replays, without a robot, to the same estimate (bit for bit); the
recording is a dataset Foxglove reads: lossless pictures, naoloc's lens as the camera
calibration, REP-105 frames (map -> odom -> base_link -> camera), odometry in ``odom``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from naoloc.app.cli import main
from tests.rooms import PIPELINE_ROOM as ROOM
from tests.rooms import run_json

AT = ["1.4", "2.2", "0.6"]  # room frame


@pytest.fixture(scope="module")
def mapped(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    tmp = tmp_path_factory.mktemp("rec")
    cfg = tmp / "f.yaml"
    cfg.write_text(yaml.safe_dump(ROOM), encoding="utf-8")
    assert main(["survey", "-c", str(cfg), "-o", str(tmp / "s.mcap")]) == 0
    assert (
        main(["build-map", "-c", str(cfg), "-d", str(tmp / "s.mcap"), "-o", str(tmp / "m.npz")])
        == 0
    )
    return cfg, tmp / "m.npz"


@pytest.mark.slow
def test_a_recorded_localization_replays_to_the_same_estimate(
    mapped: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg, vmap = mapped
    capsys.readouterr()
    rec = tmp_path / "loc.mcap"
    live = run_json(
        ["localize", "-c", str(cfg), "-m", str(vmap), "--at", *AT, "--record", str(rec)], capsys
    )
    assert live["status"] == "tracking" and live["record"] == str(rec) and rec.is_file()
    again = run_json(["replay", str(rec), "-m", str(vmap)], capsys)
    assert again["same"] is True and again["verb"] == "localize" and again["complete"]
    assert again["pictures"] == live["images"] and again["observations"] >= live["images"]
    for key in ("x", "y", "theta"):  # the live JSON rounds to 4 digits, the replay does not
        assert round(again[key], 4) == live[key]
        assert again[key] == again["recorded"][key]
    assert again["covariance"] == again["recorded"]["covariance"]


@pytest.mark.slow
@pytest.mark.parametrize("verb", ["track", "go-home"])
def test_track_and_go_home_record_and_replay(
    verb: str, mapped: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg, vmap = mapped
    capsys.readouterr()
    rec = tmp_path / f"{verb}.mcap"
    extra = ["--duration", "1.5"] if verb == "track" else []
    run_json(
        [verb, "-c", str(cfg), "-m", str(vmap), "--at", *AT, "--record", str(rec), *extra], capsys
    )
    again = run_json(["replay", str(rec), "-m", str(vmap)], capsys)
    assert again["same"] is True and again["verb"] == verb


@pytest.mark.slow
def test_a_recording_is_a_rep105_dataset_with_the_lens_calibration(
    mapped: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mcap.reader import make_reader

    from naoloc.data.dataset import _protobuf_fields, read_dataset

    cfg, vmap = mapped
    capsys.readouterr()
    rec = tmp_path / "loc.mcap"
    run_json(
        ["localize", "-c", str(cfg), "-m", str(vmap), "--at", *AT, "--record", str(rec)], capsys
    )
    data = read_dataset(rec)  # a dataset: the pictures read back, lossless
    assert data.meta["recording"] == "localize" and len(data.keyframes) >= 2
    with open(rec, "rb") as f:
        reader = make_reader(f)
        tfs = {
            (tf[2][0], tf[3][0])
            for tf in (_protobuf_fields(m.data) for _, _, m in reader.iter_messages(topics=["/tf"]))
        }
        odom = [
            _protobuf_fields(m.data) for _, _, m in reader.iter_messages(topics=["/pose/odometry"])
        ]
        est = list(reader.iter_messages(topics=["/pose/estimate"]))
        cov = list(reader.iter_messages(topics=["/pose/estimate/odometry"]))
        assert len(cov) == len(est) > 0  # with the covariance, as live
        maps = {
            c.topic for _, c, _ in reader.iter_messages(topics=["/map/keyframes", "/map/landmarks"])
        }
    assert maps == {"/map/keyframes", "/map/landmarks"}  # the map, as the live view shows it
    assert {(b"map", b"odom"), (b"odom", b"base_link"), (b"base_link", b"camera")} <= tfs
    assert (b"room", b"map") in tfs and (b"map", b"base_link") not in tfs
    assert all(o[2] == [b"odom"] for o in odom) and est


@pytest.mark.slow
def test_replay_refuses_a_survey(
    mapped: tuple[Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    _, vmap = mapped
    capsys.readouterr()
    assert main(["replay", str(vmap.with_name("s.mcap")), "-m", str(vmap)]) == 1
    assert "not a recording" in capsys.readouterr().err


def test_the_calibration_is_the_lens_the_images_have() -> None:
    from naoloc.data.dataset import calibration
    from naoloc.robot.keyframe import CameraInfo
    from naoloc.robot.lens import NAO_LENS

    cam = CameraInfo(320, 240)
    k, d = calibration(cam, NAO_LENS)
    assert (k[0], k[4]) == (278.5, 278.5) and (k[2], k[5]) == (154.25, 115.25)
    assert d == [-0.055, 0.0, 0.0, 0.0, 0.0]
    k0, d0 = calibration(cam, None)  # no lens: the ideal pinhole of the field of view
    assert d0 == [0.0] * 5 and k0[2] == 160.0


@pytest.mark.slow
def test_the_map_picture_counts_what_it_draws(
    mapped: tuple[Path, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import numpy as np

    from naoloc.mapping import load_map
    from naoloc.viz import plots

    figures: list[Any] = []
    monkeypatch.setattr(plots, "save_figure", lambda fig, path: figures.append(fig) or path)
    vmap = load_map(mapped[1])
    plots.plot_map(vmap, tmp_path / "m.png")
    ax = figures[0].axes[0]
    neurons = next(line for line in ax.lines if str(line.get_label()).startswith("neurons"))
    drawn = len(neurons.get_xdata())
    title = ax.get_title()
    assert f"{drawn} neurons with images at {vmap.distinct_poses} distinct poses" in title
    assert drawn == int(np.all(np.isfinite(vmap.neuron_poses), axis=1).sum())
    labels = [str(line.get_label()) for line in ax.lines]
    assert any(label.startswith("landmarks (") for label in labels)
    assert any(label.startswith("survey path (") for label in labels)


@pytest.mark.slow
def test_track_refuses_a_goal_off_the_map_before_connecting(
    mapped: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _, vmap = mapped
    nao = tmp_path / "nao.yaml"  # a closed port: connecting would fail with "cannot connect"
    nao.write_text(yaml.safe_dump({"robot": {"backend": "naoqi", "url": "tcp://127.0.0.1:9"}}))
    capsys.readouterr()
    code = main(["track", "-c", str(nao), "-m", str(vmap), "--to", "90", "90"])
    err = capsys.readouterr().err
    assert code == 1 and "is not on the map's free floor" in err and "connect" not in err
