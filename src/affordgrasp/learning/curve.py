"""Learning curves: nested subsets of a training split and the trend of a score with its size.

A learning curve trains one recipe on nested subsets of the training rows and scores each
on the same held-out rows (``studies/learning_curve.py``, docs/learning.md, "Learning
curve"). This module holds its parts that do not train:

* :func:`object_order` and :func:`keep_mask`: the subsets, nested (a smaller point keeps a
  prefix of a larger one's objects, or of its samples);
* :func:`fit_log_trend`: comparison accuracy against log(training rows) by least squares,
  and the rows that would reach a goal if the trend held;
* :func:`curve_settings` and :func:`check_settings`: a finished point is reused only when
  it was measured with the same settings.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError


def object_order(objects, families, seed: int) -> list[str]:
    """The training objects, one of every family in turn (families and instances shuffled).

    Parameters
    ----------
    objects : (n,) str
        Object names (one per row: repeats allowed).
    families : (n,) str
        The family of each entry of ``objects``.
    seed : int
        Seed of the shuffles.

    Returns
    -------
    list of str
        Every distinct object once; its first k entries take the families in turn, so any
        prefix is spread over the families.
    """
    rng = np.random.default_rng(seed)
    by_family: dict[str, list[str]] = {}
    for name, fam in sorted(set(zip(objects, families, strict=True))):
        by_family.setdefault(fam, []).append(name)
    fams = [str(f) for f in rng.permutation(sorted(by_family))]
    queues = {f: [str(o) for o in rng.permutation(by_family[f])] for f in fams}
    order = []
    while any(queues.values()):
        for f in fams:
            if queues[f]:
                order.append(queues[f].pop(0))
    return order


def keep_mask(samples, point: str, order: list[str], per_object: int) -> np.ndarray:
    """The training rows a point of the curve keeps.

    Parameters
    ----------
    samples : Samples
        Training rows (``object`` and ``sample`` are read).
    point : str
        ``objects:F`` (the first fraction F of ``order``, every sample), ``samples:F``
        (every object, the samples numbered below F × ``per_object``) or ``all``.
    order : list of str
        The object order (:func:`object_order`).
    per_object : int
        Samples per object.

    Returns
    -------
    (n,) bool
        The kept rows.

    Raises
    ------
    InputError
        For an unknown point or a fraction outside (0, 1] (``samples:F``: F > 0).
    """
    if point == "all":
        return np.ones(len(samples.object), bool)
    kind, _, frac = point.partition(":")
    if kind not in ("objects", "samples"):
        raise InputError(f"unknown point {point!r}; use objects:F, samples:F or all")
    try:
        f = float(frac)
    except ValueError:
        raise InputError(f"point {point!r}: the fraction {frac!r} is not a number") from None
    if not 0 < f <= (math.inf if kind == "samples" else 1):
        raise InputError(f"point {point!r}: the fraction must be in (0, 1] (samples: > 0)")
    if kind == "objects":
        n = max(1, round(f * len(order)))
        return np.isin(samples.object, order[:n])
    return samples.sample < round(f * per_object)


def fit_log_trend(points: list[dict[str, Any]], goal: float) -> dict[str, Any] | None:
    """comparison = a + b·ln(rows) by least squares, and the rows that would reach ``goal``.

    Parameters
    ----------
    points : list of dict
        Each with ``train_rows`` (int) and ``comparison_accuracy`` (float).
    goal : float
        The comparison accuracy to reach.

    Returns
    -------
    dict or None
        ``n``, ``slope_per_ln_rows`` (b) and its standard error ``slope_se``,
        ``per_doubling`` (b ln 2), ``residual_sd``, ``mean_se``, and ``rows_for_goal``
        with ``rows_for_goal_slope_plus_se`` / ``_minus_se`` (+inf where the trend never
        reaches the goal, or beyond any float); None with fewer than 3 points or a
        single row count.
    """
    x = np.log([p["train_rows"] for p in points])
    y = np.array([p["comparison_accuracy"] for p in points])
    n = len(x)
    if n < 3 or np.ptp(x) == 0:
        return None
    xm, ym = x.mean(), y.mean()
    sxx = float(((x - xm) ** 2).sum())
    b = float(((x - xm) * (y - ym)).sum() / sxx)
    resid = y - (ym + b * (x - xm))
    s = math.sqrt(float((resid**2).sum()) / (n - 2))
    se_b, se_mean = s / math.sqrt(sxx), s / math.sqrt(n)

    def rows_for(slope: float) -> float:
        if slope <= 0:
            return math.inf
        exponent = xm + (goal - ym) / slope
        # A nearly flat curve puts the goal beyond any float: never reached, not an overflow.
        return math.exp(exponent) if exponent < 700.0 else math.inf

    return {
        "n": n,
        "slope_per_ln_rows": b,
        "slope_se": se_b,
        "per_doubling": b * math.log(2),
        "residual_sd": s,
        "mean_se": se_mean,
        "rows_for_goal": rows_for(b),
        "rows_for_goal_slope_plus_se": rows_for(b + se_b),
        "rows_for_goal_slope_minus_se": rows_for(b - se_b),
    }


def curve_settings(
    data: str | os.PathLike, order_seed: int, sigma: float, base_samples: int | None
) -> dict[str, Any]:
    """What a point's result depends on besides its file name (model, copies, seed, point).

    Parameters
    ----------
    data : str or path-like
        The dataset (stored resolved).
    order_seed : int
        Seed of :func:`object_order`.
    sigma : float
        Standard deviation of the perturbed copies, in p0's units.
    base_samples : int or None
        Samples per object of one block of copies (None: the dataset's).

    Returns
    -------
    dict
        JSON-ready.
    """
    return {
        "data": str(Path(data).resolve()),
        "order_seed": order_seed,
        "sigma": sigma,
        "base_samples": base_samples,
    }


def check_settings(path: str | os.PathLike, settings: dict[str, Any]) -> None:
    """Refuse to reuse a finished point measured with other settings (a resumed run is fine).

    Parameters
    ----------
    path : str or path-like
        A point's JSON file, with its ``settings``.
    settings : dict
        This run's :func:`curve_settings`.

    Raises
    ------
    InputError
        When the file's settings differ (or it has none).
    """
    stored = json.loads(Path(path).read_text()).get("settings")
    if stored != settings:
        raise InputError(
            f"{path} was measured with {stored}, not {settings}: use another --out, "
            "or delete that file to measure it again"
        )
