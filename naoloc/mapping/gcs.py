"""Growing Cell Structures (Fritzke 1994), unsupervised, with insertion and removal.

The network is a 2-D cell complex (triangles) whose cells carry weight vectors in the
input space. Training follows Algorithm 1 of the paper (Fritzke's GCS):

* adaptation: winner ``s`` moves by ``eps_b (x - w_s)``, its direct neighbours by
  ``eps_n (x - w_c)``; the winner's signal counter grows by one and every counter decays
  by the fraction ``alpha`` per step;
* every ``lambda`` steps, while the network is smaller than its target size: insert a
  cell halfway between the cell ``q`` with the largest counter and its farthest neighbour
  ``f``, splitting every triangle that holds the edge q-f, and hand it the counter share
  each new neighbour loses (Voronoi volumes estimated from mean edge lengths); then remove
  the cells whose estimated probability density falls below ``eta`` and the cells left
  outside every triangle.

Volume trap: Fritzke estimates a region's volume as (mean edge length)^n; with n the
input dimension (hundreds of histogram bins) that underflows to 0 and gives NaN. Here
volumes use the complex's own dimension (``volume_dim``, 2) and densities are compared
in log space relative to the mean (``p = h_c / (F_c / sum F)``), so they stay finite and
removal keeps working for any input dimension.

Speed (few inputs, "Gram mode"): every cell keeps, next to its weights, its squared
distance to every input, ``D[c, j] = |w_c - x_j|^2``. A step ``w' = (1 - e) w + e x_i``
changes that row exactly by the polarisation identity

    ``D'[c, j] = (1 - e) D[c, j] + e Q[i, j] - e (1 - e) D[c, i]``,  ``Q[i, j] = |x_i - x_j|^2``,

so the winner of input ``i`` is the argmin of one column and a step touches only the
winner's and its neighbours' rows, O(inputs + dimension) each, as one small matrix
product (see :class:`_Trainer`). Everything stays float64, and deterministic:
same seed, same network, bit for bit. Many inputs ("direct mode"): one matrix-vector
product per step against cached squared norms.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import chain
from typing import Any

import numpy as np

from naoloc.errors import NaolocError


@dataclass(frozen=True, slots=True)
class GCSParams:
    """Learning parameters (Fritzke's typical values for 2-D complexes).

    Attributes:
        eps_b: Winner learning rate.
        eps_n: Neighbour learning rate.
        alpha: Signal-counter decay per adaptation step; None = ``1 / (10 * target)`` so
            the counters remember about ten signals per cell.
        lambda_steps: Adaptation steps between insertions (at most; fewer when the step
            budget would not reach the target size otherwise).
        eta: Removal threshold on the relative probability density (1 = average).
        volume_dim: Exponent of the mean edge length in the volume estimate.
        removal: Remove low-density cells (Fritzke's removal step).
        grow_fraction: Share of the adaptation steps within which growth must finish;
            the rest only adapts the final structure.
        removal_every: Check for removal after every this many insertions.
    """

    eps_b: float = 0.06
    eps_n: float = 0.002
    alpha: float | None = None
    lambda_steps: int = 100
    eta: float = 0.09
    volume_dim: int = 2
    removal: bool = True
    grow_fraction: float = 0.8
    removal_every: int = 4


@dataclass(frozen=True)
class GCSNetwork:
    """A trained network.

    Attributes:
        weights: ``(K, d)`` float64 cell weights in the input space.
        triangles: ``(T, 3)`` int64 cell indices of the complex's triangles.
        inserted: Cells inserted during training.
        removed: Cells removed during training.
        steps: Adaptation steps performed.
    """

    weights: np.ndarray
    triangles: np.ndarray
    inserted: int = 0
    removed: int = 0
    steps: int = 0

    @property
    def size(self) -> int:
        """Number of cells."""
        return int(self.weights.shape[0])

    def edges(self) -> np.ndarray:
        """``(E, 2)`` int64 sorted unique edges of the complex."""
        return complex_edges(self.triangles)

    def winners(self, x: np.ndarray) -> np.ndarray:
        """Index ``(n,)`` of the nearest cell (Euclidean) for each input row."""
        return nearest_rows(np.atleast_2d(x), self.weights)


def nearest_rows(x: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Index of the nearest row of ``w`` for each row of ``x`` (squared Euclidean)."""
    if w.shape[0] == 0:
        return np.zeros(x.shape[0], np.int64)
    w_sq = np.einsum("ij,ij->i", w, w)
    return np.argmin(w_sq[None, :] - 2.0 * (x @ w.T), axis=1).astype(np.int64)


def complex_edges(triangles: np.ndarray) -> np.ndarray:
    """Unique sorted edges ``(E, 2)`` of a set of triangles ``(T, 3)``."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [0, 2]]])
    e.sort(axis=1)
    return np.unique(e, axis=0) if e.size else np.zeros((0, 2), np.int64)


def complex_problems(triangles: np.ndarray, cells: int) -> list[str]:
    """What is wrong with a 2-D cell complex (empty list when valid).

    Valid: every triangle has three distinct cells in range, no triangle repeats, every
    cell lies in a triangle, and every edge belongs to one or two triangles.
    """
    problems: list[str] = []
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if t.size == 0:
        return ["no triangles"]
    if t.min() < 0 or t.max() >= cells:
        problems.append("cell index out of range")
    st = np.sort(t, axis=1)
    if np.any(st[:, 0] == st[:, 1]) or np.any(st[:, 1] == st[:, 2]):
        problems.append("degenerate triangle")
    if np.unique(st, axis=0).shape[0] != st.shape[0]:
        problems.append("repeated triangle")
    if np.unique(t).size != cells:
        problems.append("cell outside every triangle")
    e = np.concatenate([st[:, [0, 1]], st[:, [1, 2]], st[:, [0, 2]]])
    _, counts = np.unique(e, axis=0, return_counts=True)
    if counts.max() > 2:
        problems.append("edge shared by more than two triangles")
    return problems


class _IndexStream:
    """Training-input order: a fresh seeded permutation of the inputs for every epoch."""

    def __init__(self, n: int, rng: np.random.Generator):
        self._n = n
        self._rng = rng
        self._buf = np.zeros(0, np.int64)

    def take(self, count: int) -> np.ndarray:
        while self._buf.size < count:
            self._buf = np.concatenate([self._buf, self._rng.permutation(self._n)])
        out, self._buf = self._buf[:count], self._buf[count:]
        return out


def _pair_sq_dist(w: np.ndarray, ia: np.ndarray, ib: np.ndarray) -> np.ndarray:
    """Squared Euclidean distances between the paired rows ``w[ia]`` and ``w[ib]``.

    Works in blocks of a few dozen rows: large temporaries would cost more in page faults
    than the arithmetic.
    """
    out = np.empty(ia.size)
    step = max(1, 16384 // max(w.shape[1], 1))
    for s in range(0, ia.size, step):
        diff = w[ia[s : s + step]]  # not take(): it copies a non-contiguous view whole
        diff -= w[ib[s : s + step]]
        out[s : s + step] = np.einsum("ij,ij->i", diff, diff)
    return out


class _Trainer:
    """Mutable training state; see the module docstring for the algorithm.

    Gram mode (few inputs): one array ``big`` holds, per cell row ``c < kmax``,
    ``[w_c (d) | D[c] (n)]`` with ``D[c, j] = |w_c - x_j|^2``; row ``kmax`` is
    ``[0 | 1]`` and row ``kmax + 1 + j`` is ``[x_j | Q[j]]`` with ``Q[j, l] = |x_j - x_l|^2``.
    Unused cell rows hold ``D = inf`` so the winner of input ``i`` is the argmin of the
    fixed column view ``big[:kmax, d + i]``. A step with learning rates ``e`` on the
    rows ``idx`` is the single product ``K @ big[idx + [kmax, kmax + 1 + i]]`` with
    ``K = [diag(1 - e) | -e (1 - e) D[idx, i] | e]`` (see the module docstring).

    Direct mode (many inputs): ``big`` holds the weights only and a cached squared norm
    per cell gives the winner from one matrix-vector product per step.
    """

    def __init__(
        self,
        x: np.ndarray,
        target: int,
        params: GCSParams,
        rng: np.random.Generator,
        gram_mode: bool | None = None,
    ):
        n, d = x.shape
        self.x = x
        self.n, self.d = n, d
        self.p = params
        # Winner from cached distances when the inputs are few (None: choose by size).
        self.gram_mode = n <= 2 * d + 64 if gram_mode is None else gram_mode
        self.gdiag = np.einsum("ij,ij->i", x, x)
        kmax = max(target, 3)
        self.kmax = kmax
        if self.gram_mode:
            self.big = np.zeros((kmax + 1 + n, d + n))
            self.big[:kmax, d:] = np.inf
            self.big[kmax, d:] = 1.0
            self.big[kmax + 1 :, :d] = x
            q = self.gdiag[:, None] + self.gdiag[None, :] - 2.0 * (x @ x.T)
            np.maximum(q, 0.0, out=q)
            np.fill_diagonal(q, 0.0)
            self.big[kmax + 1 :, d:] = q
            self.cols = [self.big[:kmax, d + j] for j in range(n)]
        else:
            self.big = np.zeros((kmax, d))
        self.w = self.big[:kmax, :d]
        self.sq = np.zeros(kmax)  # |w_c|^2, maintained in direct mode only
        self.tau = np.zeros(kmax)
        self.inc = 1.0
        alpha = params.alpha if params.alpha is not None else 1.0 / (10.0 * kmax)
        self.grow = 1.0 / (1.0 - alpha)
        start = rng.choice(n, 3, replace=n < 3)
        scale = float(np.abs(x).max()) or 1.0
        self.w[:3] = x[start] + rng.normal(0.0, 1e-6 * scale, (3, d))  # distinct even on ties
        self.k = 3
        # Triangles keyed by their sorted cells, in creation order: (serial, oriented cells).
        self.tris: dict[tuple[int, ...], tuple[int, tuple[int, int, int]]] = {}
        self.serial = 0
        self._add_tri((0, 1, 2))
        self.nbrs: list[set[int]] = [{1, 2}, {0, 2}, {0, 1}]
        self.cache: dict[int, tuple[Any, ...]] = {}
        self.templates: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self.inserted = 0
        self.removed = 0
        self.refresh_rows(list(range(3)))

    def _add_tri(self, t: tuple[int, int, int]) -> None:
        self.tris[tuple(sorted(t))] = (self.serial, t)
        self.serial += 1

    def triangles(self) -> list[tuple[int, int, int]]:
        """The complex's triangles in creation order."""
        return [t for _, t in self.tris.values()]

    def refresh_rows(self, rows: list[int]) -> None:
        """Recompute the cached distances (or norms) of some cells from their weights."""
        ix = np.asarray(rows, dtype=np.int64)
        w = self.w[ix]
        sq = np.einsum("ij,ij->i", w, w)
        if self.gram_mode:
            dist = sq[:, None] + self.gdiag[None, :] - 2.0 * (w @ self.x.T)
            self.big[ix, self.d :] = np.maximum(dist, 0.0)
        else:
            self.sq[ix] = sq

    def _template(self, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per-size step matrix ``K`` (Fortran order), its free column and ``-e (1 - e)``."""
        tpl = self.templates.get(m)
        if tpl is None:
            e = np.full(m, self.p.eps_n)
            e[0] = self.p.eps_b
            mat = np.zeros((m, m + 2), order="F")
            mat[np.arange(m), np.arange(m)] = 1.0 - e
            mat[:, m + 1] = e
            tpl = (mat, mat[:, m], -(e * (1.0 - e)))
            self.templates[m] = tpl
        return tpl

    def _entry(self, s: int) -> tuple[Any, ...]:
        """Cached step data of winner ``s`` (valid until its neighbourhood changes)."""
        cells = [s, *sorted(self.nbrs[s])]
        m = len(cells)
        if self.gram_mode:
            ix = np.array([*cells, self.kmax, self.kmax + 1], dtype=np.int64)
            mat, col, neom = self._template(m)
            ent: tuple[Any, ...] = (ix[:m], ix, mat, col, neom, m)
        else:
            e = np.full((m, 1), self.p.eps_n)
            e[0] = self.p.eps_b
            ent = (np.array(cells, dtype=np.int64), 1.0 - e, e)
        self.cache[s] = ent
        return ent

    def adapt(self, order: np.ndarray) -> None:
        """Present the inputs ``order`` one by one (the hot loop)."""
        if self.gram_mode:
            self._adapt_gram(order)
        else:
            self._adapt_direct(order)

    def _adapt_gram(self, order: np.ndarray) -> None:
        big, cols, tau, cache = self.big, self.cols, self.tau, self.cache
        inc, grow, d, toff = self.inc, self.grow, self.d, self.kmax + 1
        multiply = np.multiply
        for i in order.tolist():
            s = int(cols[i].argmin())
            ent = cache.get(s)
            if ent is None:
                ent = self._entry(s)
            idx, ix, mat, col, neom, m = ent
            ix[m + 1] = toff + i
            z = big.take(ix, 0)
            multiply(z[:m, d + i], neom, out=col)
            big[idx] = mat @ z
            tau[s] += inc
            inc *= grow
        self.inc = inc

    def _adapt_direct(self, order: np.ndarray) -> None:
        big, sq, x, tau, cache, k = self.big, self.sq, self.x, self.tau, self.cache, self.k
        inc, grow = self.inc, self.grow
        w, sqk = big[:k], sq[:k]
        for i in order.tolist():
            xi = x[i]
            s = int(np.argmin(sqk - 2.0 * (w @ xi)))
            ent = cache.get(s)
            if ent is None:
                ent = self._entry(s)
            idx, om, e = ent
            r = big.take(idx, 0)
            r *= om
            r += e * xi
            big[idx] = r
            sq[idx] = np.einsum("ij,ij->i", r, r)
            tau[s] += inc
            inc *= grow
        self.inc = inc

    def normalise_counters(self) -> None:
        """Fold the pending decay into the counters (true counters, scale 1)."""
        self.tau[: self.k] /= self.inc
        self.inc = 1.0

    def _log_mean_len(self, cells: list[int], nbrs: list[set[int]]) -> np.ndarray:
        """Log of the mean edge length (input units) from ``cells[j]`` to ``nbrs[j]``.

        One batched distance computation for all pairs; ``-inf`` where a set is empty.
        """
        owner: list[int] = []
        src: list[int] = []
        dst: list[int] = []
        for j, (c, nb) in enumerate(zip(cells, nbrs, strict=True)):
            owner += [j] * len(nb)
            src += [c] * len(nb)
            dst += nb
        own = np.asarray(owner, dtype=np.int64)
        w = self.w
        length = np.sqrt(_pair_sq_dist(w, np.asarray(src), np.asarray(dst)))
        count = np.bincount(own, minlength=len(cells))
        mean = np.bincount(own, length, minlength=len(cells)) / np.maximum(count, 1)
        out = np.log(np.maximum(mean, 1e-300))
        out[count == 0] = -np.inf
        return out

    def insert(self) -> None:
        """Insert a cell between the most-signalled cell and its farthest neighbour."""
        k, w, tau, nbrs = self.k, self.w, self.tau, self.nbrs
        q = int(np.argmax(tau[:k]))
        nq = np.fromiter(sorted(nbrs[q]), np.int64)
        f = int(nq[int(np.argmax(_pair_sq_dist(w, nq, np.full_like(nq, q))))])
        hits = []
        for xv in nbrs[q] & nbrs[f]:
            key = tuple(sorted((q, f, xv)))
            found = self.tris.get(key)
            if found is not None:
                hits.append((found[0], xv, key))
        hits.sort()  # creation order of the split triangles
        xs = [xv for _, xv, _ in hits]
        r = k
        around = [q, f, *xs]
        w[r] = 0.5 * (w[q] + w[f])
        self.refresh_rows([r])
        # Mean edge lengths around the split edge before and after the split, in one batch.
        before = [nbrs[c] for c in around]
        after = [(nbrs[q] - {f}) | {r}, (nbrs[f] - {q}) | {r}, *[nbrs[c] | {r} for c in xs]]
        logs = self._log_mean_len(around + around, before + after)
        old, new = logs[: len(around)], logs[len(around) :]
        for _, _, key in hits:
            del self.tris[key]
        for xv in xs:
            self._add_tri((q, r, xv))
            self._add_tri((r, f, xv))
        for c, nb in zip(around, after, strict=True):
            nbrs[c] = nb
        nbrs.append(set(around))
        self.k = k + 1
        ratio = np.exp(np.minimum(0.0, self.p.volume_dim * (new - old)))
        given = 0.0
        for c, kept in zip(around, ratio.tolist(), strict=True):
            share = float(tau[c]) * (1.0 - kept)  # the part of c's region r takes over
            tau[c] -= share
            given += share
        tau[r] = given
        for c in [*around, r]:
            self.cache.pop(c, None)
        self.inserted += 1

    def log_density(self) -> np.ndarray:
        """Log relative probability density ``log(h_c / (F_c / sum F))`` of every cell."""
        k, kmax = self.k, self.kmax
        t = np.fromiter(chain.from_iterable(self.tris), np.int64, 3 * len(self.tris))
        a, b, c = t[0::3], t[1::3], t[2::3]  # keys hold sorted cells: a < b < c
        keys = np.unique(np.concatenate([a * kmax + b, b * kmax + c, a * kmax + c]))
        e = np.stack([keys // kmax, keys % kmax], axis=1)
        length = np.sqrt(_pair_sq_dist(self.w, e[:, 0], e[:, 1]))
        sums = np.bincount(e.ravel(), np.repeat(length, 2), minlength=k)
        degree = np.bincount(e.ravel(), minlength=k)
        log_mean = np.log(np.maximum(sums / np.maximum(degree, 1), 1e-300))
        log_vol = self.p.volume_dim * log_mean
        top = log_vol.max()
        log_rel_vol = log_vol - (top + np.log(np.exp(log_vol - top).sum()))
        total = self.tau[:k].sum()
        with np.errstate(divide="ignore"):
            log_h = np.log(self.tau[:k] / total) if total > 0 else np.zeros(k)
        return log_h - log_rel_vol

    def remove(self, max_remove: int) -> None:
        """Remove up to ``max_remove`` cells below the density threshold ``eta``."""
        if max_remove <= 0 or self.k <= 3:
            return
        logp = self.log_density()
        low = np.flatnonzero(logp < np.log(self.p.eta))
        if low.size == 0:
            return
        low = low[np.argsort(logp[low], kind="stable")][:max_remove]
        dead = set(low.tolist())
        tris = [t for t in self.triangles() if not dead.intersection(t)]
        alive = sorted({v for t in tris for v in t})
        if len(alive) < 3:
            return
        remap = {old: new for new, old in enumerate(alive)}
        keep = np.asarray(alive, dtype=np.int64)
        n_keep = keep.size
        self.big[:n_keep] = self.big[keep]
        self.sq[:n_keep] = self.sq[keep]
        self.tau[:n_keep] = self.tau[keep]
        if self.gram_mode:
            self.big[n_keep : self.k, self.d :] = np.inf
        self.tris = {}
        self.nbrs = [set() for _ in range(n_keep)]
        for t in tris:
            a, b, c = remap[t[0]], remap[t[1]], remap[t[2]]
            self._add_tri((a, b, c))
            self.nbrs[a].update((b, c))
            self.nbrs[b].update((a, c))
            self.nbrs[c].update((a, b))
        self.removed += self.k - n_keep
        self.k = n_keep
        self.cache.clear()


def train_gcs(
    data: np.ndarray, target: int, epochs: int, seed: int, params: GCSParams | None = None
) -> GCSNetwork:
    """Train an unsupervised GCS on the rows of ``data``.

    Args:
        data: ``(n, d)`` inputs, e.g. image histograms.
        target: Network size to grow to (cells), at least 3.
        epochs: Passes over the data; ``epochs * n`` adaptation steps in all.
        seed: Seed of the initial cells and the input order (same seed, same network).
        params: Learning parameters; defaults to :class:`GCSParams`.

    Returns:
        The trained network.

    Raises:
        NaolocError: When there is no data or the target is below 3.
    """
    return _train(data, target, epochs, seed, params or GCSParams(), None)


def _train(
    data: np.ndarray,
    target: int,
    epochs: int,
    seed: int,
    p: GCSParams,
    gram_mode: bool | None,
) -> GCSNetwork:
    """:func:`train_gcs` with the winner search forced to Gram or direct mode (tests)."""
    x = np.ascontiguousarray(data, dtype=np.float64)
    if x.ndim != 2 or x.shape[0] == 0:
        raise NaolocError(f"GCS needs a non-empty 2-D array of inputs, got shape {x.shape}")
    if target < 3:
        raise NaolocError(f"GCS target size must be at least 3, got {target}")
    rng = np.random.default_rng(seed)
    tr = _Trainer(x, target, p, rng, gram_mode)
    stream = _IndexStream(x.shape[0], rng)
    total = int(epochs) * x.shape[0]
    grow_end = int(p.grow_fraction * total)
    t = 0
    chunk = 4096
    while t < total:
        if tr.k < target:
            need = target - tr.k
            end = grow_end if t < grow_end else total
            lam = max(1, min(p.lambda_steps, (end - t) // need, total - t))
            tr.adapt(stream.take(lam))
            t += lam
            tr.normalise_counters()
            tr.insert()
            if p.removal and tr.k < target and tr.inserted % p.removal_every == 0:
                # Remove only as many cells as can still be re-grown at >= lambda/4 spacing.
                spacing = max(1, p.lambda_steps // 4)
                tr.remove(max(0, (end - t) // spacing - (target - tr.k)))
        else:
            step = min(chunk, total - t)
            tr.adapt(stream.take(step))
            t += step
    k = tr.k
    return GCSNetwork(
        weights=tr.w[:k].copy(),
        triangles=np.asarray(tr.triangles(), dtype=np.int64).reshape(-1, 3),
        inserted=tr.inserted,
        removed=tr.removed,
        steps=t,
    )
