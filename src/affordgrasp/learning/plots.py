"""PNG plots of model metrics: precision–recall curves, GMS cumulative distributions,
predicted vs true values.

Headless without touching the caller's matplotlib: each plot is a
:class:`matplotlib.figure.Figure` of its own (no pyplot, never ``matplotlib.use``), written
by its Agg canvas, so a notebook's or an application's backend stays as it was.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..runtime.writing import atomic_write
from .evaluation import gms_distribution, precision_recall


def _subplots(*grid: int, figsize: tuple[float, float], dpi: int = 120, **kwargs):
    """A figure of its own and its axes (``Figure.subplots``: ``grid``, ``sharex``...)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi)
    return fig, fig.subplots(*grid, **kwargs)


def _save(fig, path) -> Path:
    """Write a figure atomically, in the format its file's suffix names (PNG by default)."""
    return atomic_write(path, lambda fh: fig.savefig(fh, format=Path(path).suffix[1:] or None))


def plot_pr_curves(path, curves: dict[str, tuple[np.ndarray, np.ndarray]], positive_rate: float):
    """Precision-recall curves; the dashed line is the predict-the-mean baseline.

    Parameters
    ----------
    path : path
        The PNG file.
    curves : dict of str to (labels, scores)
        Label → ((n,) bool truth, (n,) float scores).
    positive_rate : float
        Share of positives (the baseline's precision).

    Returns
    -------
    pathlib.Path
    """
    fig, ax = _subplots(figsize=(5, 4))
    for label, (y, s) in curves.items():
        precision, recall, _ = precision_recall(y, s)
        ax.step(np.r_[0.0, recall], np.r_[precision[0], precision], where="pre", label=label)
    ax.axhline(positive_rate, ls="--", c="grey", label=f"baseline ({positive_rate:.2f})")
    ax.set(xlabel="recall", ylabel="precision", xlim=(0, 1), ylim=(0, 1.02))
    ax.set_title("Precision-recall, held-out objects")
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def plot_gms_cdf(path, runs: dict[str, tuple[np.ndarray, np.ndarray]], *, lower_is_better=True):
    """Cumulative GMS distributions, E[GMS] as lines.

    Parameters
    ----------
    path : path
        The PNG file.
    runs : dict of str to (truth, predictions)
        Label → ((n,) float, (n,) float).
    lower_is_better : bool
        The target ranks low values first.

    Returns
    -------
    pathlib.Path
    """
    fig, ax = _subplots(figsize=(5, 4))
    for label, (t, p) in runs.items():
        g = np.sort(gms_distribution(t, p, lower_is_better=lower_is_better))
        line = ax.plot(g, np.arange(1, len(g) + 1) / len(g), label=f"{label} (E={g.mean():.2f})")
        ax.axvline(g.mean(), c=line[0].get_color(), ls=":")
    ax.set(xlabel="GMS", ylabel="cumulative share of 10% subsets", xlim=(0, 1), ylim=(0, 1))
    ax.set_title("Global Min Score, held-out objects")
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def plot_scatter(path, truth: np.ndarray, pred: np.ndarray, label: str):
    """Predicted against true values (normalised), with the diagonal.

    Parameters
    ----------
    path : path
        The PNG file.
    truth, pred : (n,) float ndarray
    label : str
        The title.

    Returns
    -------
    pathlib.Path
    """
    fig, ax = _subplots(figsize=(4.5, 4.5))
    ax.scatter(truth, pred, s=4, alpha=0.4)
    lo = float(min(np.min(truth), np.min(pred)))
    hi = float(max(np.max(truth), np.max(pred)))
    ax.plot([lo, hi], [lo, hi], c="grey", ls="--")
    ax.set(xlabel="true (normalised)", ylabel="predicted (normalised)", title=label)
    fig.tight_layout()
    return _save(fig, path)


def plot_reliability(path, runs: dict[str, tuple[np.ndarray, np.ndarray]], *, bins: int = 10):
    """Reliability diagram: observed positive rate against predicted probability.

    Parameters
    ----------
    path : path
        The PNG file.
    runs : dict of str to (labels, probabilities)
        Label → ((n,) bool truth, (n,) float probabilities).
    bins : int
        Equal-width probability bins.

    Returns
    -------
    pathlib.Path
    """
    from .evaluation import expected_calibration_error, reliability_bins

    fig, (ax, hist) = _subplots(
        2, 1, figsize=(5, 5.5), sharex=True, gridspec_kw={"height_ratios": [3, 1]}
    )
    ax.plot([0, 1], [0, 1], ls="--", c="grey", label="calibrated")
    for label, (y, p) in runs.items():
        r = reliability_bins(y, p, bins=bins)
        ece = expected_calibration_error(y, p, bins=bins)
        full = r["count"] > 0
        ax.plot(
            r["mean_probability"][full],
            r["positive_rate"][full],
            marker="o",
            label=f"{label} (ECE {ece:.3f})",
        )
        centres = 0.5 * (r["edges"][:-1] + r["edges"][1:])
        hist.bar(centres, r["count"], width=1.0 / bins, alpha=0.5, label=label)
    ax.set(ylabel="observed viable rate", xlim=(0, 1), ylim=(0, 1.02))
    ax.set_title("Reliability, held-out objects")
    ax.legend(loc="upper left", fontsize=8)
    hist.set(xlabel="predicted probability", ylabel="rows")
    hist.set_yscale("log")
    fig.tight_layout()
    return _save(fig, path)
