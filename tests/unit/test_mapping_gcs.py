"""Growing Cell Structures on toy distributions: growth, topology, removal, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from naoloc.errors import NaolocError
from naoloc.mapping.gcs import (
    GCSParams,
    _IndexStream,
    _train,
    _Trainer,
    complex_problems,
    train_gcs,
)


def _two_blobs(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.uniform([0.0, 0.0], [1.0, 1.0], (n, 2))
    b = rng.uniform([2.0, 0.0], [3.0, 1.0], (n, 2))
    return np.concatenate([a, b])


def _in_gap(w: np.ndarray) -> int:
    return int(((w[:, 0] > 1.1) & (w[:, 0] < 1.9)).sum())


def test_grows_to_target_with_valid_complex() -> None:
    x = np.random.default_rng(0).uniform(0.0, 1.0, (400, 2))
    net = train_gcs(x, 40, 20, seed=0)
    assert net.size == 40
    assert complex_problems(net.triangles, net.size) == []
    assert np.isfinite(net.weights).all()
    # The cells spread over the unit square.
    assert net.weights.min(axis=0).max() < 0.2 and net.weights.max(axis=0).min() > 0.8


def test_same_seed_same_network_other_seed_differs() -> None:
    x = np.random.default_rng(1).normal(size=(200, 2))
    a = train_gcs(x, 25, 10, seed=3)
    b = train_gcs(x, 25, 10, seed=3)
    c = train_gcs(x, 25, 10, seed=4)
    assert np.array_equal(a.weights, b.weights) and np.array_equal(a.triangles, b.triangles)
    assert not np.array_equal(a.weights, c.weights)


def test_removal_clears_the_empty_region() -> None:
    x = _two_blobs(300, 2)
    kept = train_gcs(x, 60, 20, seed=0, params=GCSParams(removal=False))
    pruned = train_gcs(x, 60, 20, seed=0)
    assert kept.removed == 0 and pruned.removed > 0
    assert _in_gap(pruned.weights) < _in_gap(kept.weights)
    assert _in_gap(pruned.weights) == 0
    assert complex_problems(pruned.triangles, pruned.size) == []
    assert pruned.size == 60


def test_high_dimensional_histograms_keep_removal_and_stay_finite() -> None:
    rng = np.random.default_rng(5)
    h = rng.random((60, 256)) ** 6
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    net = train_gcs(h, 30, 20, seed=0)
    assert np.isfinite(net.weights).all()
    assert net.removed > 0  # (mean edge)^256 would underflow; removal must still work
    assert net.size == 30
    assert complex_problems(net.triangles, net.size) == []


def test_bad_inputs_raise_naoloc_errors() -> None:
    with pytest.raises(NaolocError):
        train_gcs(np.zeros((0, 4)), 10, 1, seed=0)
    with pytest.raises(NaolocError):
        train_gcs(np.zeros((5, 4)), 2, 1, seed=0)


def test_identical_inputs_do_not_break_training() -> None:
    net = train_gcs(np.ones((20, 8)), 10, 5, seed=0)
    assert np.isfinite(net.weights).all() and net.size == 10


def _histograms(n: int, seed: int) -> np.ndarray:
    h = np.random.default_rng(seed).random((n, 64)) ** 6
    return h / np.linalg.norm(h, axis=1, keepdims=True)


def test_histograms_same_seed_same_network_bit_for_bit() -> None:
    h = _histograms(50, 8)  # few inputs: the cached-distance (Gram) winner search
    a = train_gcs(h, 20, 15, seed=1)
    b = train_gcs(h, 20, 15, seed=1)
    assert np.array_equal(a.weights, b.weights) and np.array_equal(a.triangles, b.triangles)
    assert (a.inserted, a.removed, a.steps) == (b.inserted, b.removed, b.steps)


@pytest.mark.parametrize("data", ["histograms", "plane"])
def test_cached_and_direct_winner_search_train_the_same_network(data: str) -> None:
    x = _histograms(60, 9) if data == "histograms" else _two_blobs(80, 3)
    gram = _train(x, 30, 15, 2, GCSParams(), gram_mode=True)
    direct = _train(x, 30, 15, 2, GCSParams(), gram_mode=False)
    assert gram.removed > 0 and gram.inserted > 27
    assert (gram.inserted, gram.removed) == (direct.inserted, direct.removed)
    assert np.array_equal(gram.triangles, direct.triangles)
    assert np.allclose(gram.weights, direct.weights, rtol=0.0, atol=1e-12)


def test_cached_distances_follow_the_weights() -> None:
    x = _histograms(40, 4)
    rng = np.random.default_rng(0)
    tr = _Trainer(x, 25, GCSParams(), rng, gram_mode=True)
    stream = _IndexStream(x.shape[0], rng)
    while tr.k < 25:
        tr.adapt(stream.take(37))
        tr.normalise_counters()
        tr.insert()
        if tr.inserted % 3 == 0:
            tr.remove(2)
    tr.adapt(stream.take(500))
    assert tr.removed > 0
    k, d = tr.k, x.shape[1]
    exact = ((tr.w[:k, None, :] - x[None, :, :]) ** 2).sum(axis=2)
    assert np.allclose(tr.big[:k, d:], exact, rtol=0.0, atol=1e-12)
    assert np.isinf(tr.big[k : tr.kmax, d:]).all()  # free rows never win
    assert complex_problems(np.asarray(tr.triangles()), k) == []
