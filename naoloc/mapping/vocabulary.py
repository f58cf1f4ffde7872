"""Visual vocabulary: k-majority (Hamming) or k-means (Euclidean) words, TF-IDF histograms.

Binary descriptors are unpacked to 0/1 bits; on such vectors the squared Euclidean
distance is the Hamming distance, so k-means with centres thresholded at 0.5 is
k-majority clustering (DBoW2/DBoW3). SIFT descriptors use plain Euclidean k-means.
Image vectors are TF-IDF weighted: ``v_i = (n_id / n_d) * log(N / N_i)``.

Speed: Hamming distances to bit centres are computed on the packed bytes by OpenCV
(``cv2.batchDistance`` with ``NORM_HAMMING``, the kernel of ``BFMatcher``) instead of a float
matrix product over unpacked bits, and the k-majority vote sums bits per word with one
``np.add.reduceat`` over the descriptors sorted by word instead of ``np.add.at``. Both give
exactly the old results: Hamming distances and bit counts are small integers (exact in
float32 too), and a tie goes to the lowest word index in both (``np.argmin`` and OpenCV's
strict ``<`` scan). SIFT keeps the float path unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from naoloc.errors import FeatureError

# Descriptors drawn from the training images to cluster (the rest are only assigned).
MAX_TRAIN_DESCRIPTORS = 10000
KMEANS_ITERATIONS = 10


def descriptor_vectors(desc: np.ndarray, binary: bool) -> np.ndarray:
    """Descriptors as float32 vectors: unpacked bits for binary kinds, as-is for SIFT."""
    if binary:
        return np.unpackbits(np.ascontiguousarray(desc, dtype=np.uint8), axis=1).astype(np.float32)
    return np.asarray(desc, dtype=np.float32)


def pack_bits(bits: np.ndarray) -> np.ndarray:
    """0/1 float rows (unpacked bits) packed back into uint8 bytes, as ``np.packbits``."""
    return np.packbits(np.asarray(bits) >= 0.5, axis=1)


# Packed binary descriptors are zero-padded to a multiple of this many bytes before OpenCV's
# Hamming kernels: the same distances, and its SIMD popcount then covers every byte
# (A-KAZE's 61 bytes leave a 13-byte tail it counts byte by byte): 1.5-1.7x faster matching
# (tools/bench_localize.py).
PAD_BYTES = 16


def pad_packed(desc: np.ndarray) -> np.ndarray:
    """Packed binary rows ``desc`` (uint8) zero-padded to a multiple of :data:`PAD_BYTES`."""
    desc = np.ascontiguousarray(desc, dtype=np.uint8)
    width = desc.shape[1]
    if width % PAD_BYTES == 0:
        return desc
    out = np.zeros((desc.shape[0], width + PAD_BYTES - width % PAD_BYTES), np.uint8)
    out[:, :width] = desc
    return out


def hamming_nearest(packed: np.ndarray, packed_centres: np.ndarray) -> np.ndarray:
    """Index ``(n,)`` int64 of the nearest centre of each packed binary row.

    Ties go to the lowest centre index (as ``np.argmin`` of the distances would).

    Args:
        packed: ``(n, b)`` uint8 descriptors.
        packed_centres: ``(k, b)`` uint8 centres.
    """
    import cv2

    if packed.shape[0] == 0:
        return np.zeros(0, np.int64)
    _dist, idx = cv2.batchDistance(
        pad_packed(packed),
        pad_packed(packed_centres),
        cv2.CV_32S,
        normType=cv2.NORM_HAMMING,
        K=1,
    )
    return np.asarray(idx, dtype=np.int64).reshape(-1)


def hamming_to(packed: np.ndarray, packed_centre: np.ndarray) -> np.ndarray:
    """Hamming distance ``(n,)`` float32 of each packed row to one packed centre."""
    import cv2

    dist, _idx = cv2.batchDistance(
        pad_packed(packed), pad_packed(packed_centre[None, :]), cv2.CV_32S,
        normType=cv2.NORM_HAMMING, K=1,
    )  # fmt: skip
    return np.asarray(dist, dtype=np.float32).reshape(-1)


def bit_counts(packed: np.ndarray, labels: np.ndarray, k: int) -> np.ndarray:
    """Per label, how many rows have each bit set: ``(k, 8 b)`` float32.

    Equal to ``np.add.at(sums, labels, unpackbits(packed))`` (integers, so exactly), by one
    ``np.add.reduceat`` over the rows sorted by label.
    """
    sums = np.zeros((k, packed.shape[1] * 8), np.float32)
    if packed.shape[0] == 0:
        return sums
    order = np.argsort(labels, kind="stable")
    sorted_labels = labels[order]
    starts = np.flatnonzero(np.r_[True, sorted_labels[1:] != sorted_labels[:-1]])
    bits = np.unpackbits(packed[order], axis=1)
    sums[sorted_labels[starts]] = np.add.reduceat(bits, starts, axis=0, dtype=np.int32)
    return sums


def _sq_dists(x: np.ndarray, c: np.ndarray, c_sq: np.ndarray) -> np.ndarray:
    """Squared distances ``(n, k)`` between rows of x and centres c (Hamming on bits)."""
    x_sq = np.einsum("ij,ij->i", x, x)
    d = x_sq[:, None] + c_sq[None, :] - 2.0 * (x @ c.T)
    np.maximum(d, 0.0, out=d)
    return d


@dataclass(frozen=True)
class Vocabulary:
    """A trained vocabulary.

    Attributes:
        centres: ``(k, d)`` float32 word centres (0/1 bits for binary descriptors).
        idf: ``(k,)`` float64 inverse document frequencies ``log(N / N_i)``.
        binary: True when words live in Hamming space.
    """

    centres: np.ndarray
    idf: np.ndarray
    binary: bool

    def __post_init__(self) -> None:
        c = np.ascontiguousarray(self.centres, dtype=np.float32)
        object.__setattr__(self, "_centres_t", np.ascontiguousarray(c.T))
        object.__setattr__(self, "_centres_sq", np.einsum("ij,ij->i", c, c))
        packed = pack_bits(c) if self.binary else np.zeros((0, 0), np.uint8)
        object.__setattr__(self, "_centres_packed", packed)

    @property
    def size(self) -> int:
        """Number of words."""
        return int(self.centres.shape[0])

    def assign(self, desc: np.ndarray) -> np.ndarray:
        """Word index ``(n,)`` int64 of each descriptor (nearest centre).

        Raises:
            FeatureError: Descriptors of another kind or width than the words (e.g. ORB
                descriptors against an A-KAZE map).
        """
        width = self.centres.shape[1] // 8 if self.binary else self.centres.shape[1]
        if desc.ndim != 2 or desc.shape[1] != width or (desc.dtype == np.uint8) != self.binary:
            kind = "binary" if self.binary else "float"
            raise FeatureError(
                f"descriptors {desc.dtype} x {desc.shape[1:]} do not fit this vocabulary of "
                f"{kind} words of {width} {'bytes' if self.binary else 'values'} "
                "(a map built with another feature kind?)"
            )
        if desc.shape[0] == 0:
            return np.zeros(0, np.int64)
        if self.binary:
            packed: np.ndarray = self._centres_packed  # type: ignore[attr-defined]
            return hamming_nearest(np.asarray(desc, dtype=np.uint8), packed)
        x = descriptor_vectors(desc, self.binary)
        c_sq: np.ndarray = self._centres_sq  # type: ignore[attr-defined]
        c_t: np.ndarray = self._centres_t  # type: ignore[attr-defined]
        # argmin |x - c|^2 = argmin (|c|^2 - 2 x.c): |x|^2 is constant per row.
        return np.argmin(c_sq[None, :] - 2.0 * (x @ c_t), axis=1).astype(np.int64)

    def tfidf(self, words: np.ndarray) -> np.ndarray:
        """TF-IDF vector ``(k,)`` float64 of an image's word indices (zeros when empty)."""
        counts = np.bincount(words, minlength=self.size).astype(np.float64)
        total = counts.sum()
        if total == 0:
            return counts
        return counts / total * self.idf

    def histogram(self, desc: np.ndarray) -> np.ndarray:
        """L2-normalised TF-IDF histogram ``(k,)`` float64 of an image's descriptors."""
        return l2_normalise(self.tfidf(self.assign(desc)))

    def histograms(self, descriptor_sets: Sequence[np.ndarray]) -> np.ndarray:
        """``(N, k)`` histograms of many images at once, row i equal to ``histogram(set i)``.

        All descriptors are assigned in one call and counted with one ``np.bincount``.
        """
        n = len(descriptor_sets)
        if n == 0:
            return np.zeros((0, self.size))
        sizes = [d.shape[0] for d in descriptor_sets]
        nonempty = [d for d in descriptor_sets if d.shape[0]]
        words = self.assign(np.concatenate(nonempty)) if nonempty else np.zeros(0, np.int64)
        image = np.repeat(np.arange(n), sizes)
        counts = np.bincount(image * self.size + words, minlength=n * self.size)
        counts = counts.reshape(n, self.size).astype(np.float64)
        total = counts.sum(axis=1, keepdims=True)
        tf = np.divide(counts, total, out=np.zeros_like(counts), where=total > 0)
        return l2_normalise(np.where(total > 0, tf * self.idf, counts))


def l2_normalise(v: np.ndarray) -> np.ndarray:
    """Rows (or a vector) scaled to unit L2 norm; zero rows stay zero."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v, dtype=np.float64), where=n > 0)


def l1_normalise(v: np.ndarray) -> np.ndarray:
    """Rows (or a vector) scaled to unit L1 norm; zero rows stay zero."""
    n = np.abs(v).sum(axis=-1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v, dtype=np.float64), where=n > 0)


def dbow_scores(query: np.ndarray, database: np.ndarray) -> np.ndarray:
    """DBoW2 L1 scores ``1 - 0.5 |q/|q|_1 - d/|d|_1|_1`` in [0, 1] of one query against rows.

    An empty histogram (an image without keypoints) is no evidence of anything: it scores 0,
    not the 0.5 the formula would give it (which beat most true matches).
    """
    q = l1_normalise(query)
    if not np.any(q):
        return np.zeros(database.shape[0])
    norms = np.abs(database).sum(axis=1)
    d = np.divide(database, norms[:, None], out=np.zeros(database.shape), where=norms[:, None] > 0)
    scores = 1.0 - 0.5 * np.abs(d - q[None, :]).sum(axis=1)
    scores[norms == 0] = 0.0
    return scores


def _init_centres(
    x: np.ndarray, k: int, rng: np.random.Generator, packed: np.ndarray | None = None
) -> np.ndarray:
    """k-means++ seeding (distance-squared sampling) on the rows of x.

    With ``packed`` (the rows of binary ``x`` as packed bytes) the squared distances are
    Hamming distances counted on the bytes: the same float32 values, found faster.
    """
    n = x.shape[0]
    centres = np.empty((k, x.shape[1]), np.float32)
    first = int(rng.integers(n))
    centres[0] = x[first]
    if packed is not None:
        packed = pad_packed(packed)  # once, not per centre
        best = hamming_to(packed, packed[first])
    else:
        x_sq = np.einsum("ij,ij->i", x, x)
        best = np.maximum(x_sq - 2.0 * (x @ centres[0]) + float(centres[0] @ centres[0]), 0.0)
    for j in range(1, k):
        total = float(best.sum())
        idx = int(rng.integers(n)) if total <= 0 else int(rng.choice(n, p=best / total))
        centres[j] = x[idx]
        if packed is not None:
            d = hamming_to(packed, packed[idx])
        else:
            d = np.maximum(x_sq - 2.0 * (x @ centres[j]) + float(centres[j] @ centres[j]), 0.0)
        np.minimum(best, d, out=best)
    return centres


def _assign_and_sum(
    x: np.ndarray, packed: np.ndarray | None, centres: np.ndarray, c_sq: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One k-means assignment: per-word counts (float32), sums of x per word, labels."""
    k = centres.shape[0]
    if packed is not None:  # bits: Hamming on bytes, integer bit counts by reduceat
        labels = hamming_nearest(packed, pack_bits(centres))
        sums = bit_counts(packed, labels, k)
    else:
        labels = np.argmin(c_sq[None, :] - 2.0 * (x @ centres.T), axis=1)
        sums = np.zeros_like(centres)
        np.add.at(sums, labels, x)
    counts = np.bincount(labels, minlength=k).astype(np.float32)
    return counts, sums, labels


def train_vocabulary(
    descriptor_sets: Sequence[np.ndarray], size: int, binary: bool, seed: int
) -> Vocabulary:
    """Cluster descriptors into words and compute IDF over the images.

    Args:
        descriptor_sets: One ``(n_i, d)`` descriptor array per training image.
        size: Number of words wanted (fewer when there are fewer distinct descriptors).
        binary: Hamming-space k-majority when True, Euclidean k-means otherwise.
        seed: Seed of sampling and initialisation.

    Returns:
        The vocabulary; a single all-zero word when no image has any descriptor.
    """
    rng = np.random.default_rng(seed)
    nonempty = [d for d in descriptor_sets if d.shape[0] > 0]
    width = descriptor_vectors(descriptor_sets[0][:0], binary).shape[1] if descriptor_sets else 8
    if not nonempty:
        return Vocabulary(np.zeros((1, width), np.float32), np.zeros(1), binary)
    all_desc = np.concatenate(nonempty, axis=0)
    if all_desc.shape[0] > MAX_TRAIN_DESCRIPTORS:
        pick = np.sort(rng.choice(all_desc.shape[0], MAX_TRAIN_DESCRIPTORS, replace=False))
        all_desc = all_desc[pick]
    x = descriptor_vectors(all_desc, binary)
    packed = np.ascontiguousarray(all_desc, dtype=np.uint8) if binary else None
    k = int(min(size, x.shape[0]))
    centres = _init_centres(x, k, rng, packed)
    for _ in range(KMEANS_ITERATIONS):
        c_sq = np.einsum("ij,ij->i", centres, centres)
        counts, sums, labels = _assign_and_sum(x, packed, centres, c_sq)
        new = sums / np.maximum(counts, 1.0)[:, None]
        if binary:
            new = (new >= 0.5).astype(np.float32)  # k-majority: bitwise majority vote
        empty = counts == 0
        if empty.any():  # reseed empty words on the descriptors farthest from their word
            far = _sq_dists(x, centres, c_sq)[np.arange(x.shape[0]), labels]
            new[empty] = x[np.argsort(-far, kind="stable")[: int(empty.sum())]]
        if np.array_equal(new, centres):
            break
        centres = new
    vocab = Vocabulary(centres, np.zeros(k), binary)
    n_images = len(descriptor_sets)
    doc_freq = np.zeros(k)
    for d in descriptor_sets:
        if d.shape[0]:
            doc_freq[np.unique(vocab.assign(d))] += 1
    idf = np.log(n_images / np.maximum(doc_freq, 1.0))
    return Vocabulary(centres, idf, binary)
