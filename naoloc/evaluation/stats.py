"""Error statistics of localization runs: per-estimate errors, summaries and CDFs.

All positions are in the map frame (m) and headings in radians; summaries report metres
and degrees.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from naoloc.geometry import wrap_angles


@dataclass(frozen=True, slots=True)
class ErrorSummary:
    """Summary of a set of localization errors.

    Attributes:
        n: Number of estimates.
        median_m: Median position error (m).
        p90_m: 90th percentile position error (m, linear interpolation).
        max_m: Largest position error (m).
        mean_m: Mean position error (m).
        median_heading_deg: Median absolute heading error (degrees).
        within_0_3m: Fraction of estimates within 0.3 m of the truth.
    """

    n: int
    median_m: float
    p90_m: float
    max_m: float
    mean_m: float
    median_heading_deg: float
    within_0_3m: float

    def to_dict(self) -> dict[str, float | int]:
        """JSON-able dict with the field names of the summary."""
        return {
            "n": self.n,
            "median_error_m": self.median_m,
            "p90_error_m": self.p90_m,
            "max_error_m": self.max_m,
            "mean_error_m": self.mean_m,
            "median_heading_error_deg": self.median_heading_deg,
            "within_0_3m": self.within_0_3m,
        }


def position_errors(truth: np.ndarray, estimates: np.ndarray) -> np.ndarray:
    """Euclidean errors between ``(N, >=2)`` truth and estimate positions (m)."""
    t = np.asarray(truth, dtype=np.float64).reshape(len(truth), -1)[:, :2]
    e = np.asarray(estimates, dtype=np.float64).reshape(len(estimates), -1)[:, :2]
    if t.shape != e.shape:
        raise ValueError(f"truth {t.shape} and estimates {e.shape} differ in shape")
    return np.hypot(e[:, 0] - t[:, 0], e[:, 1] - t[:, 1])


def heading_errors(truth_theta: np.ndarray, est_theta: np.ndarray) -> np.ndarray:
    """Absolute wrapped heading errors (rad) between two arrays of headings (rad)."""
    diff = np.asarray(est_theta, dtype=np.float64) - np.asarray(truth_theta, dtype=np.float64)
    return np.abs(wrap_angles(diff))


def percentile(values: np.ndarray, q: float) -> float:
    """Linear-interpolation percentile (numpy's default) that tolerates +inf values.

    Args:
        values: 1-D array; +inf stands for a failed estimate.
        q: Percentile in [0, 100].

    Returns:
        The percentile; +inf when it falls on or interpolates toward an infinite value.
    """
    v = np.sort(np.asarray(values, dtype=np.float64).ravel())
    pos = q / 100.0 * (len(v) - 1)
    lo, hi = math.floor(pos), math.ceil(pos)
    frac = pos - lo
    if frac == 0.0 or lo == hi:
        return float(v[lo])
    if not math.isfinite(v[hi]):
        return math.inf
    return float(v[lo] + (v[hi] - v[lo]) * frac)


def summarize(
    errors_m: Sequence[float] | np.ndarray, heading_errors_rad: Any = None
) -> ErrorSummary:
    """Summarize position errors (m) and optional absolute heading errors (rad).

    Args:
        errors_m: Position errors in metres; NaN (no estimate) counts as infinitely wrong in
            the percentiles and is left out of the mean.
        heading_errors_rad: Absolute heading errors in radians, or None.

    Returns:
        The summary; every figure is NaN when there are no errors.
    """
    err = np.asarray(errors_m, dtype=np.float64).ravel()
    n = int(err.size)
    if n == 0:
        nan = float("nan")
        return ErrorSummary(0, nan, nan, nan, nan, nan, nan)
    ranked = np.where(np.isnan(err), np.inf, err)
    finite = err[np.isfinite(err)]
    head = np.asarray([] if heading_errors_rad is None else heading_errors_rad, dtype=np.float64)
    head = head[np.isfinite(head)]
    return ErrorSummary(
        n=n,
        median_m=percentile(ranked, 50),
        p90_m=percentile(ranked, 90),
        max_m=float(np.max(ranked)),
        mean_m=float(np.mean(finite)) if finite.size else float("nan"),
        median_heading_deg=math.degrees(float(np.median(head))) if head.size else float("nan"),
        within_0_3m=float(np.mean(ranked <= 0.3)),
    )


def cdf(errors_m: Sequence[float] | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Empirical cumulative distribution: sorted errors (m) and fractions in (0, 1]."""
    err = np.sort(np.asarray(errors_m, dtype=np.float64).ravel())
    err = err[np.isfinite(err)]
    total = max(1, len(np.asarray(errors_m).ravel()))
    return err, np.arange(1, len(err) + 1, dtype=np.float64) / total


def group_rows(records: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Group estimate records into the summary's ``positions`` rows.

    Args:
        records: Dicts with ``group`` (int), ``truth`` ([x, y, theta] map frame) and
            ``estimate`` ([x, y, theta] map frame) and ``error_m``.

    Returns:
        One row per group in first-seen order: ``{"truth": [x, y], "estimates": [[x, y], ...],
        "mean_error_m": ...}`` (map frame, m), plus ``group`` and ``errors_m``.
    """
    rows: dict[int, dict[str, Any]] = {}
    for rec in records:
        row = rows.setdefault(
            int(rec["group"]),
            {
                "group": int(rec["group"]),
                "truth": [round(float(v), 4) for v in rec["truth"][:2]],
                "estimates": [],
                "errors_m": [],
            },
        )
        est = [float(v) for v in rec["estimate"][:2]]
        # No estimate: null in JSON (a miss), never a placeholder position.
        found = all(math.isfinite(v) for v in est)
        row["estimates"].append([round(v, 4) for v in est] if found else None)
        row["errors_m"].append(json_float(float(rec["error_m"])))
    out = []
    for row in rows.values():
        errors = [math.inf if e is None else e for e in row["errors_m"]]
        row["mean_error_m"] = json_float(float(np.mean(errors)))
        out.append(row)
    return out


def json_float(value: float, digits: int = 4) -> float | None:
    """A float rounded for JSON, or None for NaN/inf (JSON has no NaN)."""
    if value is None or not math.isfinite(value):
        return None
    return round(float(value), digits)


def integrity(records: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """How honest a set of localizations is (map frame, the ``estimates.json`` records).

    Returns:
        ``n``; ``no_estimate`` (share without a pose); of those with a pose: the share
        outside their reported 99 % position ellipse (``outside_99``; about 1 % when the
        covariance is calibrated), the count more than 0.3 m off at confidence >= 0.5
        (``confident_wrong``), the position error's median, p90 and p99 (m) and the heading
        error's p90 (deg); ``not_mapped``: how many said "not the mapped room".
    """
    n = len(records)
    posed = [r for r in records if r.get("covariance") is not None and r.get("error_m") is not None
             and math.isfinite(float(r["error_m"]))]  # fmt: skip
    d2 = []
    for r in posed:
        cov = np.asarray(r["covariance"], dtype=np.float64)[:2, :2]
        err = np.asarray(r["estimate"][:2], np.float64) - np.asarray(r["truth"][:2], np.float64)
        d2.append(float(err @ np.linalg.solve(cov, err)))
    errs = np.array([float(r["error_m"]) for r in posed])
    heads = np.array([float(r["heading_error_deg"]) for r in posed])
    conf = np.array([float(r.get("confidence", 0.0)) for r in posed])
    chi2_99 = -2.0 * math.log(0.01)  # 2 degrees of freedom
    out: dict[str, Any] = {
        "n": n,
        "no_estimate": json_float((n - len(posed)) / n) if n else None,
        "not_mapped": sum(1 for r in records if r.get("status") == "not the mapped room"),
        "outside_99": json_float(float(np.mean(np.array(d2) > chi2_99))) if d2 else None,
        "confident_wrong": int(np.sum((errs > 0.3) & (conf >= 0.5))) if posed else 0,
    }
    if posed:
        out.update(
            median_m=json_float(float(np.median(errs))),
            p90_m=json_float(float(np.quantile(errs, 0.9))),
            p99_m=json_float(float(np.quantile(errs, 0.99))),
            heading_p90_deg=json_float(float(np.quantile(heads, 0.9)), 2),
        )
    return out
