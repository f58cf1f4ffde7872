"""The packed-Hamming vocabulary equals the float k-majority it replaced, ties included."""

from __future__ import annotations

import numpy as np
import pytest

from naoloc.mapping.vocabulary import (
    Vocabulary,
    bit_counts,
    descriptor_vectors,
    hamming_nearest,
    pack_bits,
    train_vocabulary,
)


def _float_nearest(desc: np.ndarray, centres_bits: np.ndarray) -> np.ndarray:
    """The former assignment: argmin of |c|^2 - 2 x.c over unpacked bits (first on ties)."""
    x = descriptor_vectors(desc, True)
    c_sq = np.einsum("ij,ij->i", centres_bits, centres_bits)
    return np.argmin(c_sq[None, :] - 2.0 * (x @ centres_bits.T), axis=1)


def _float_train(sets: list[np.ndarray], size: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The former k-majority training (float distances, np.add.at sums): centres and IDF."""
    rng = np.random.default_rng(seed)
    all_desc = np.concatenate([d for d in sets if d.shape[0]])
    if all_desc.shape[0] > 10000:
        all_desc = all_desc[np.sort(rng.choice(all_desc.shape[0], 10000, replace=False))]
    x = descriptor_vectors(all_desc, True)
    n, k = x.shape[0], min(size, x.shape[0])
    x_sq = np.einsum("ij,ij->i", x, x)
    centres = np.empty((k, x.shape[1]), np.float32)
    centres[0] = x[rng.integers(n)]
    best = np.maximum(x_sq - 2.0 * (x @ centres[0]) + float(centres[0] @ centres[0]), 0.0)
    for j in range(1, k):
        total = float(best.sum())
        idx = int(rng.integers(n)) if total <= 0 else int(rng.choice(n, p=best / total))
        centres[j] = x[idx]
        d = np.maximum(x_sq - 2.0 * (x @ centres[j]) + float(centres[j] @ centres[j]), 0.0)
        np.minimum(best, d, out=best)
    for _ in range(10):
        labels = _float_nearest(all_desc, centres)
        counts = np.bincount(labels, minlength=k).astype(np.float32)
        sums = np.zeros_like(centres)
        np.add.at(sums, labels, x)
        new = ((sums / np.maximum(counts, 1.0)[:, None]) >= 0.5).astype(np.float32)
        empty = counts == 0
        if empty.any():
            c_sq = np.einsum("ij,ij->i", centres, centres)
            d = np.maximum(x_sq[:, None] + c_sq[None, :] - 2.0 * (x @ centres.T), 0.0)
            far = d[np.arange(n), labels]
            new[empty] = x[np.argsort(-far, kind="stable")[: int(empty.sum())]]
        if np.array_equal(new, centres):
            break
        centres = new
    doc = np.zeros(k)
    for d in sets:
        if d.shape[0]:
            doc[np.unique(_float_nearest(d, centres))] += 1
    return centres, np.log(len(sets) / np.maximum(doc, 1.0))


def _clustered_descriptors(seed: int, images: int = 30) -> list[np.ndarray]:
    """Binary descriptors near a few prototypes (many exact Hamming ties between words)."""
    rng = np.random.default_rng(seed)
    protos = rng.integers(0, 256, (12, 8), dtype=np.uint8)
    out = []
    for _ in range(images):
        n = int(rng.integers(0, 60))
        d = protos[rng.integers(0, 12, n)].copy()
        flips = rng.integers(0, 64, (n, 2))
        for row, (a, b) in enumerate(flips.tolist()):
            d[row, a // 8] ^= np.uint8(1 << (a % 8))
            d[row, b // 8] ^= np.uint8(1 << (b % 8))
        out.append(d)
    return out


def test_hamming_nearest_breaks_ties_like_argmin() -> None:
    rng = np.random.default_rng(0)
    centres = rng.integers(0, 256, (6, 4), dtype=np.uint8)
    centres = np.concatenate([centres, centres[::-1]])  # every distance tied twice
    desc = rng.integers(0, 256, (500, 4), dtype=np.uint8)
    bits = descriptor_vectors(centres, True)
    got = hamming_nearest(desc, centres)
    assert np.array_equal(got, _float_nearest(desc, bits))
    assert got.max() < 6  # the lower index of each tied pair
    assert np.array_equal(pack_bits(bits), centres)


def test_bit_counts_equal_add_at() -> None:
    rng = np.random.default_rng(1)
    packed = rng.integers(0, 256, (300, 5), dtype=np.uint8)
    labels = rng.integers(0, 9, 300)
    labels[labels == 4] = 3  # an empty word
    ref = np.zeros((9, 40), np.float32)
    np.add.at(ref, labels, descriptor_vectors(packed, True))
    assert np.array_equal(bit_counts(packed, labels, 9), ref)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_training_equals_the_float_k_majority(seed: int) -> None:
    sets = _clustered_descriptors(seed)
    vocab = train_vocabulary(sets, 16, True, seed)
    centres, idf = _float_train(sets, 16, seed)
    assert np.array_equal(vocab.centres, centres)
    assert np.array_equal(vocab.idf, idf)
    for d in sets:
        assert np.array_equal(vocab.assign(d), _float_nearest(d, centres))


def test_batch_histograms_equal_one_by_one() -> None:
    sets = _clustered_descriptors(3)
    sets[4] = sets[4][:0]  # an image without keypoints
    vocab = train_vocabulary(sets, 16, True, 0)
    one = np.stack([vocab.histogram(d) for d in sets])
    assert np.array_equal(vocab.histograms(sets), one)
    assert not one[4].any()
    sift = Vocabulary(np.eye(3, dtype=np.float32), np.ones(3), False)
    f = [np.eye(3, dtype=np.float32)[[0, 0, 2]], np.zeros((0, 3), np.float32)]
    assert np.array_equal(sift.histograms(f), np.stack([sift.histogram(d) for d in f]))


def test_descriptors_of_another_kind_are_refused_in_one_line() -> None:
    from naoloc.errors import FeatureError

    vocab = train_vocabulary(_clustered_descriptors(5), 16, True, 0)  # 8-byte words
    with pytest.raises(FeatureError, match="do not fit this vocabulary"):
        vocab.assign(np.zeros((3, 32), np.uint8))  # ORB-sized
    with pytest.raises(FeatureError, match="do not fit"):
        vocab.histogram(np.zeros((3, 8), np.float32))  # floats against binary words
    sift = Vocabulary(np.eye(4, dtype=np.float32), np.ones(4), False)
    with pytest.raises(FeatureError, match="float words of 4 values"):
        sift.assign(np.zeros((2, 8), np.uint8))
