"""Features, vocabulary and the map file: round trip, corruption, tampering, versions."""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from naoloc.config import MapConfig
from naoloc.errors import FeatureError, MapFormatError
from naoloc.geometry import Pose2D
from naoloc.localization import Localizer, Picture
from naoloc.localization.paper import localize_paper
from naoloc.mapping import VisualMap, build_map, load_map
from naoloc.mapping.mapfile import map_bytes
from naoloc.mapping.vocabulary import train_vocabulary
from naoloc.perception.features import FeatureExtractor
from naoloc.robot.keyframe import Keyframe


def _texture(seed: int, width: int = 1200, height: int = 240) -> np.ndarray:
    import cv2

    rng = np.random.default_rng(seed)
    img = np.full((height, width), 128, np.uint8)
    for _ in range(260):
        x, y = int(rng.integers(0, width)), int(rng.integers(0, height))
        colour = int(rng.integers(0, 256))
        if rng.random() < 0.5:
            cv2.circle(img, (x, y), int(rng.integers(3, 18)), colour, -1)
        else:
            w, h = int(rng.integers(4, 30)), int(rng.integers(4, 30))
            cv2.rectangle(img, (x, y), (x + w, y + h), colour, -1)
    return img


def synthetic_keyframes(n: int = 12, seed: int = 0) -> list[Keyframe]:
    """Views sliding along a textured strip, as if walking along a wall (head right)."""
    tex = _texture(seed)
    out = []
    for i in range(n):
        x0 = 40 + 60 * i
        out.append(Keyframe(tex[:, x0 : x0 + 320].copy(), Pose2D(0.1 * i, 0.0, 0.0), -1.5708))
    return out


@pytest.fixture(scope="module")
def small_map() -> VisualMap:
    cfg = MapConfig(neurons=8, epochs=5, vocabulary_size=32)
    return build_map(synthetic_keyframes(), cfg, meta={"room_size_m": [6.0, 6.0]})


@pytest.mark.parametrize("kind", ["akaze", "orb", "sift"])
def test_feature_kinds_and_blank_images(kind: str) -> None:
    ex = FeatureExtractor(kind)
    f = ex.extract(_texture(1)[:, :320])
    assert len(f) > 20 and f.xy.shape == (len(f), 2)
    assert f.descriptors.dtype == (np.float32 if kind == "sift" else np.uint8)
    blank = ex.extract(np.zeros((240, 320), np.uint8))
    assert len(blank) == 0 and blank.descriptors.shape[1] == f.descriptors.shape[1]
    with pytest.raises(FeatureError):
        ex.extract(np.zeros((4, 4, 4), np.float32))


def test_k_majority_vocabulary_is_binary_and_histograms_normalised() -> None:
    ex = FeatureExtractor("akaze")
    descs = [ex.extract(k.image).descriptors for k in synthetic_keyframes(12)]
    vocab = train_vocabulary(descs, 64, True, seed=0)
    assert vocab.size == 64 and set(np.unique(vocab.centres)) <= {0.0, 1.0}
    h = vocab.histogram(descs[0])
    assert np.isclose(np.linalg.norm(h), 1.0) and (h >= 0).all()
    assert not vocab.histogram(descs[0][:0]).any()


def test_build_map_reports_what_the_api_promises(small_map: VisualMap) -> None:
    m = small_map
    assert m.images == 12 and m.keyframe_poses.shape == (12, 3)
    assert m.neuron_poses.shape == (m.gcs.size, 3) and m.gcs.size == 8
    posed = np.isfinite(m.neuron_poses[:, 0])
    assert posed.any() and 1 <= m.distinct_poses <= posed.sum()
    assert set(m.timings) >= {"features_s", "vocabulary_s", "gcs_s", "total_s"}
    assert m.meta["room_size_m"] == [6.0, 6.0]


def test_round_trip_is_bit_for_bit(small_map: VisualMap, tmp_path: Path) -> None:
    path = tmp_path / "m.npz"
    small_map.save(path)
    loaded = load_map(path)
    assert map_bytes(loaded) == path.read_bytes()
    assert np.array_equal(loaded.gcs.weights, small_map.gcs.weights)
    assert loaded.meta == small_map.meta and loaded.config == small_map.config
    queries = synthetic_keyframes()[3:5]
    est = localize_paper(loaded, loaded.extract(queries), queries)
    assert est.method == "gcs" and 0.0 <= est.confidence <= 1.0


def test_blank_query_gives_zero_confidence(small_map: VisualMap) -> None:
    blank = Keyframe(np.zeros((240, 320), np.uint8), Pose2D())
    assert localize_paper(small_map, small_map.extract([blank]), [blank]).confidence == 0.0
    loc = Localizer(small_map)
    loc.update(Picture(blank))
    assert loc.pose().confidence == 0.0 and not loc.pose().found


def _rewrite(data: bytes, edit: dict[str, np.ndarray]) -> bytes:
    src = zipfile.ZipFile(io.BytesIO(data))
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as zf:
        for name in src.namelist():
            key = name[:-4]
            if key in edit:
                buf = io.BytesIO()
                np.save(buf, edit[key])
                zf.writestr(name, buf.getvalue())
            else:
                zf.writestr(name, src.read(name))
    return out.getvalue()


def test_a_version_1_map_is_read_through_the_migration(small_map: VisualMap) -> None:
    data = map_bytes(small_map)
    meta = json.loads(np.load(io.BytesIO(data))["meta_json"].tobytes())
    assert meta["version"] == 4
    meta["version"] = 1  # before the adaptive threshold and the look-ahead
    del meta["features"]["min_keypoints"], meta["features"]["akaze_threshold"]
    meta["meta"] = {**meta["meta"], "head_yaw": -1.57}
    old = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    vmap = load_map(_rewrite(data, {"meta_json": old}))
    assert vmap.feature_params["min_keypoints"] == 0
    assert vmap.feature_params["akaze_threshold"] == 0.001
    assert vmap.meta["picture_yaw"] == -1.57
    meta["version"] = 4  # a current file must name them
    with pytest.raises(MapFormatError, match="bad feature parameters"):
        load_map(_rewrite(data, {"meta_json": np.frombuffer(json.dumps(meta).encode(), np.uint8)}))


def test_a_version_2_map_drops_the_old_localizer_tuning(small_map: VisualMap) -> None:
    data = map_bytes(small_map)
    meta = json.loads(np.load(io.BytesIO(data))["meta_json"].tobytes())
    meta["version"] = 2  # its config still tuned the verified localizer
    meta["config"]["tuning"]["localizer"] = {"candidates": 5, "confident_inliers": 40.0}
    vmap = load_map(
        _rewrite(data, {"meta_json": np.frombuffer(json.dumps(meta).encode(), np.uint8)})
    )
    assert vmap.config == small_map.config
    meta["version"] = 3  # a current file may not
    with pytest.raises(MapFormatError):
        load_map(_rewrite(data, {"meta_json": np.frombuffer(json.dumps(meta).encode(), np.uint8)}))


def test_a_version_3_map_drops_the_start_heading_gate(small_map: VisualMap) -> None:
    data = map_bytes(small_map)
    meta = json.loads(np.load(io.BytesIO(data))["meta_json"].tobytes())
    meta["version"] = 3  # its build-map gated the start's heading
    meta["config"]["tuning"]["wall_poses"]["start_gate_rad"] = 0.06
    vmap = load_map(
        _rewrite(data, {"meta_json": np.frombuffer(json.dumps(meta).encode(), np.uint8)})
    )
    assert vmap.config == small_map.config
    meta["version"] = 4  # a current file may not
    with pytest.raises(MapFormatError, match="bad map config"):
        load_map(_rewrite(data, {"meta_json": np.frombuffer(json.dumps(meta).encode(), np.uint8)}))


def test_tampered_newer_and_foreign_files(small_map: VisualMap, tmp_path: Path) -> None:
    data = map_bytes(small_map)
    poses = small_map.keyframe_poses.copy()
    poses[0, 0] += 1.0
    with pytest.raises(MapFormatError, match="checksum"):
        load_map(_rewrite(data, {"keyframe_poses": poses}))
    meta = json.loads(np.load(io.BytesIO(data))["meta_json"].tobytes())
    meta["version"] = 99
    newer = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    with pytest.raises(MapFormatError, match="newer"):
        load_map(_rewrite(data, {"meta_json": newer}))
    with pytest.raises(MapFormatError):
        load_map(_rewrite(data, {"winners": np.array([object()], dtype=object)}))
    foreign = tmp_path / "foreign.npz"
    np.savez(foreign, a=np.arange(3))
    with pytest.raises(MapFormatError, match="unexpected member"):
        load_map(foreign)
    with pytest.raises(MapFormatError, match="no such"):
        load_map(tmp_path / "missing.npz")


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_corrupted_files_raise_only_map_format_error(
    small_map: VisualMap, data: st.DataObject
) -> None:
    good = map_bytes(small_map)
    kind = data.draw(st.sampled_from(["truncate", "flip", "random", "splice"]))
    if kind == "truncate":
        blob = good[: data.draw(st.integers(0, len(good) - 1))]
    elif kind == "flip":
        raw = bytearray(good)
        for pos in data.draw(st.lists(st.integers(0, len(raw) - 1), min_size=1, max_size=8)):
            raw[pos] ^= data.draw(st.integers(1, 255))
        blob = bytes(raw)
    elif kind == "random":
        blob = data.draw(st.binary(max_size=2048))
    else:
        cut = data.draw(st.integers(0, len(good)))
        blob = good[:cut] + data.draw(st.binary(min_size=1, max_size=64)) + good[cut:]
    try:
        load_map(blob)
    except MapFormatError:
        return
    # The only acceptable success is an unchanged map (e.g. a flip inside zip padding).
    assert map_bytes(load_map(blob)) == good


def test_far_pictures_leave_the_papers_map_alone(small_map: VisualMap, tmp_path: Path) -> None:
    """The survey's far pictures join the keyframes (features, landmarks, retrieval) after
    the wall pictures, each posed at its stop; the paper's vocabulary, GCS and neuron poses,
    and the wall pictures' refined poses, are those of the same map without them."""
    from naoloc.localization.paper import featured_neuron_poses

    walls = synthetic_keyframes()
    across = _texture(7)
    far = [
        (s, Keyframe(across[:, 60 * s : 60 * s + 320].copy(), walls[s].pose * Pose2D(0, 0, 0.01),
                     1.5708))
        for s in (1, 4, 7)
    ]  # fmt: skip
    cfg = MapConfig(neurons=8, epochs=5, vocabulary_size=32)
    both = build_map(walls, cfg, meta={"room_size_m": [6.0, 6.0]}, far=far)
    n = len(walls)
    assert both.images == n + 3 and both.wall_images == n and both.meta["far_pictures"] == 3
    assert both.far_images == 3 and small_map.far_images == 0
    assert small_map.wall_images == n and small_map.meta["far_pictures"] == 0
    assert np.array_equal(both.vocabulary.centres, small_map.vocabulary.centres)
    assert np.array_equal(both.gcs.weights, small_map.gcs.weights)
    assert np.array_equal(both.neuron_poses, small_map.neuron_poses, equal_nan=True)
    assert np.array_equal(both.refined_poses[:n], small_map.refined_poses)
    got, want = featured_neuron_poses(both), featured_neuron_poses(small_map)
    for g, w in zip(got, want, strict=True):
        assert np.array_equal(g, w, equal_nan=True)
    # Each far picture rides with its stop: the wall picture's refined pose, turned 0.01 rad.
    for j, (s, _kf) in enumerate(far):
        row = both.refined_poses[n + j]
        assert np.allclose(row, both.refined_poses[s] + [0.0, 0.0, 0.01], atol=1e-9)
    assert both.histograms.shape[0] == n + 3 and both.kp_offsets.shape == (n + 4,)
    back = load_map(map_bytes(both))
    assert back.wall_images == n and np.array_equal(back.refined_poses, both.refined_poses)
    with pytest.raises(Exception, match="stop is not one of the 12 keyframes"):
        build_map(walls, cfg, far=[(12, far[0][1])])


def test_a_far_picture_count_beyond_the_keyframes_is_refused(small_map: VisualMap) -> None:
    from naoloc.mapping.mapfile import checksum

    data = map_bytes(small_map)
    arrays = dict(np.load(io.BytesIO(data)))
    meta = json.loads(arrays["meta_json"].tobytes())
    for bad in (small_map.images, -1, "3", True):
        meta["meta"] = {**meta["meta"], "far_pictures": bad}
        meta["checksum"] = checksum({k: v for k, v in arrays.items() if k != "meta_json"})
        raw = np.frombuffer(json.dumps(meta).encode(), np.uint8)
        with pytest.raises(MapFormatError, match="far_pictures"):
            load_map(_rewrite(data, {"meta_json": raw}))


def _resealed(data: bytes, edit: dict[str, np.ndarray]) -> bytes:
    """The map with ``edit`` applied and its checksum made to match (a crafted file)."""
    from naoloc.mapping.mapfile import checksum

    arrays = dict(np.load(io.BytesIO(data)))
    arrays.update(edit)
    meta = json.loads(arrays["meta_json"].tobytes())
    meta["checksum"] = checksum({k: v for k, v in arrays.items() if k != "meta_json"})
    meta_json = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    return _rewrite(data, {**edit, "meta_json": meta_json})


def test_a_crafted_map_with_nan_or_infinite_values_is_refused(small_map: VisualMap) -> None:
    data = map_bytes(small_map)
    load_map(_resealed(data, {}))  # resealing alone keeps a good map good
    poses, views = small_map.neuron_poses.copy(), small_map.neuron_views.copy()
    poses[int(small_map.winners[0])] = np.nan
    with pytest.raises(MapFormatError, match="neuron_views is NaN"):
        load_map(_resealed(data, {"neuron_poses": poses}))
    both = views.copy()
    both[int(small_map.winners[0])] = np.nan
    with pytest.raises(MapFormatError, match="wins wall pictures but has no pose"):
        load_map(_resealed(data, {"neuron_poses": poses, "neuron_views": both}))
    with pytest.raises(MapFormatError, match="no neuron has a pose"):
        load_map(_resealed(data, {
            "neuron_poses": np.full_like(poses, np.nan), "neuron_views": np.full_like(views, np.nan)
        }))  # fmt: skip
    for key in ("keyframe_poses", "histograms", "refined_poses"):
        bad = getattr(small_map, key).copy()
        bad.flat[0] = np.inf
        with pytest.raises(MapFormatError, match=f"{key} holds"):
            load_map(_resealed(data, {key: bad}))
