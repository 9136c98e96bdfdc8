"""Plots of a dataset as PNG: metric distributions, status counts, affordances per object.

Every plot is computed in two streaming passes over the scalar columns (ranges, then
histograms with fixed bins), so a dataset larger than memory can be plotted. Infinite and
missing values are counted apart and written on each panel, never dropped silently.

Axis scales: a column whose finite values are all positive and span more than three decades
is binned on a log axis; one that spans zero (or holds zeros) and more than four decades, on
a symmetric-log axis; any other, linearly.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow as pa

from .figure import new_figure, save_figure

BINS = 40
PROBABLE = 0.5  # a task probability accepts a row with p_T >= PROBABLE
STATUS_COLORS = {"grasped": "#2ca02c", "touched": "#ff7f0e", "missed": "#9e9e9e"}
NOT_METRICS = ("sample", "seed", "use_triangle", "n_contacts")


@dataclass
class Summary:
    """Counts and range of one numeric column (pass 1), then its histogram (pass 2).

    Attributes
    ----------
    n, nan, pos_inf, neg_inf, zeros : int
        Values seen, and how many of them are NaN, +inf, −inf, 0.
    lo, hi : float
        Finite range.
    min_abs_nonzero : float
        Smallest finite non-zero magnitude (for a symmetric log scale).
    edges : ndarray or None
        Histogram bin edges (pass 2).
    scale : str
        ``"linear"``, ``"log"`` or ``"symlog"``.
    linthresh : float
        Linear range of the symlog scale.
    counts : ndarray or None
        Histogram counts (pass 2).
    """

    n: int = 0
    nan: int = 0
    pos_inf: int = 0
    neg_inf: int = 0
    lo: float = math.inf
    hi: float = -math.inf
    min_abs_nonzero: float = math.inf
    zeros: int = 0
    edges: np.ndarray | None = None
    scale: str = "linear"
    linthresh: float = 1.0
    counts: np.ndarray | None = None

    @property
    def finite(self) -> int:
        """How many values seen were finite."""
        return self.n - self.nan - self.pos_inf - self.neg_inf

    def see(self, values: np.ndarray) -> None:
        """Pass 1: count the values and widen the range.

        Parameters
        ----------
        values : array_like of float
            A batch of the column (NaN and infinities are counted, not ranged).
        """
        v = np.asarray(values, dtype=np.float64)
        self.n += v.size
        self.nan += int(np.isnan(v).sum())
        self.pos_inf += int(np.isposinf(v).sum())
        self.neg_inf += int(np.isneginf(v).sum())
        f = v[np.isfinite(v)]
        if f.size:
            self.lo = min(self.lo, float(f.min()))
            self.hi = max(self.hi, float(f.max()))
            nz = np.abs(f[f != 0])
            self.zeros += int(f.size - nz.size)
            if nz.size:
                self.min_abs_nonzero = min(self.min_abs_nonzero, float(nz.min()))

    def fix_bins(self, bins: int = BINS) -> None:
        """Choose the scale and the bin edges from what pass 1 saw.

        Log when the finite values are positive and span more than 10^3, symlog when the range
        is more than 10^4 times the smallest non-zero magnitude, else linear; no bins without a
        finite value.

        Parameters
        ----------
        bins : int
            Number of bins.
        """
        if self.finite == 0:
            self.edges = None
            return
        lo, hi = self.lo, self.hi
        if lo == hi:
            pad = abs(lo) * 0.05 or 0.5
            self.edges = np.linspace(lo - pad, hi + pad, bins + 1)
            self.scale = "linear"
            self.counts = np.zeros(bins, dtype=np.int64)
            return
        elif lo > 0 and hi / lo > 1e3:
            self.scale = "log"
            self.edges = np.geomspace(lo, hi, bins + 1)
        elif (
            math.isfinite(self.min_abs_nonzero)
            and max(abs(lo), abs(hi)) / self.min_abs_nonzero > 1e4
        ):
            self.scale = "symlog"
            self.linthresh = max(abs(lo), abs(hi)) * 1e-4
            t = np.linspace(_symlog(lo, self.linthresh), _symlog(hi, self.linthresh), bins + 1)
            self.edges = _symexp(t, self.linthresh)
        else:
            self.scale = "linear"
            self.edges = np.linspace(lo, hi, bins + 1)
        if lo < hi:
            self.edges[0], self.edges[-1] = lo, hi  # exact ends: the extremes fall in a bin
        self.counts = np.zeros(bins, dtype=np.int64)

    def add(self, values: np.ndarray) -> None:
        """Pass 2: add the finite values of a batch to the histogram.

        Parameters
        ----------
        values : array_like of float
        """
        if self.edges is None:
            return
        v = np.asarray(values, dtype=np.float64)
        v = v[np.isfinite(v)]
        c, _ = np.histogram(v, bins=self.edges)
        self.counts += c

    def note(self) -> str:
        """What the histogram leaves out, e.g. ``"+∞ 12%, NaN 3%"``.

        Returns
        -------
        str
            The shares of +∞, −∞ and NaN values, and of exact zeros when they are at least 20 %
            (a spike at 0 hides the rest); empty when nothing is left out.
        """
        parts = []
        for label, k in (("+∞", self.pos_inf), ("−∞", self.neg_inf), ("NaN", self.nan)):
            if k:
                parts.append(f"{label} {100.0 * k / max(self.n, 1):.0f}%")
        if self.zeros >= 0.2 * max(self.n, 1):  # a spike at 0 hides the rest: say how big
            parts.append(f"0 exactly {100.0 * self.zeros / max(self.n, 1):.0f}%")
        return ", ".join(parts)


def _symlog(x, c):
    return np.sign(x) * np.log10(1.0 + np.abs(x) / c)


def _symexp(t, c):
    return np.sign(t) * c * (10.0 ** np.abs(t) - 1.0)


def _numeric_fields(schema: pa.Schema) -> list[str]:
    return [
        f.name
        for f in schema
        if (pa.types.is_floating(f.type) or pa.types.is_integer(f.type))
        and f.name not in NOT_METRICS
    ]


def _column(table: pa.Table, name: str) -> np.ndarray:
    return table.column(name).to_numpy().astype(np.float64)


def _say_empty(ax, text: str) -> None:
    style = {"ha": "center", "va": "center", "color": "#777777", "fontsize": 9}
    ax.text(0.5, 0.5, text, transform=ax.transAxes, **style)


def _draw_hist(ax, s: Summary, color: str = "#4c72b0") -> None:
    if s.edges is None or s.counts is None or s.counts.sum() == 0:
        _say_empty(ax, "no finite value")
        ax.set_yticks([])
        return
    widths = np.diff(s.edges)
    ax.bar(s.edges[:-1], s.counts, width=widths, align="edge", color=color, edgecolor="none")
    if s.scale == "log":
        ax.set_xscale("log")
    elif s.scale == "symlog":
        ax.set_xscale("symlog", linthresh=s.linthresh)
    ax.tick_params(labelsize=7)
    ax.set_xlim(s.edges[0], s.edges[-1])


@dataclass
class DatasetSummary:
    """Everything the plots need, gathered in two passes.

    Attributes
    ----------
    rows : int
    metrics : dict of str to Summary
        Per numeric metric column.
    status : dict of str to dict
        Object -> policy status -> rows.
    reasons : dict of str to int
        ``epsilon_reason`` -> rows.
    affordances : dict of str to dict
        Task -> object -> Summary of its finite scores.
    task_ranges : dict of str to Summary
        Per task, over every object.
    """

    rows: int = 0
    metrics: dict[str, Summary] = field(default_factory=dict)
    status: dict[str, dict[str, int]] = field(default_factory=dict)  # object -> status -> n
    reasons: dict[str, int] = field(default_factory=dict)  # epsilon_reason -> n
    affordances: dict[str, dict[str, Summary]] = field(default_factory=dict)  # task -> object -> s
    task_ranges: dict[str, Summary] = field(default_factory=dict)
    # task probability -> object -> rows with p_T >= 0.5 (a probability is never -inf: its
    # rows "accepted" are the probable ones)
    probable: dict[str, dict[str, int]] = field(default_factory=dict)

    def accepted(self, task: str, obj: str) -> int:
        """Rows of an object a task accepts: a finite (or +inf) score, or for a task
        probability p_T >= 0.5.

        Parameters
        ----------
        task, obj : str

        Returns
        -------
        int
        """
        if task in self.probable:
            return self.probable[task].get(obj, 0)
        s = self.affordances.get(task, {}).get(obj)
        return 0 if s is None else s.finite + s.pos_inf


def summarize(
    scan: Callable[[Sequence[str]], Iterable[pa.Table]],
    schema: pa.Schema,
    tasks: Sequence = (),
    *,
    mode: str = "default",
    thresholds: dict[str, dict[str, float]] | None = None,
    bins: int = BINS,
    robust: bool = False,
    stored: Sequence[str] = (),
    progress: Callable[[int], object] | None = None,
) -> DatasetSummary:
    """Two passes over ``scan(columns)`` (an iterable of tables) for :func:`save_plots`.

    Parameters
    ----------
    scan : callable
        ``scan(columns)`` yields pyarrow Tables of those columns.
    schema : pyarrow.Schema
        The rows' schema.
    tasks : sequence of Task
        Tasks whose scores are plotted per object.
    mode : str
        Threshold mode.
    thresholds : dict of str to dict, optional
        Task name -> threshold overrides.
    bins : int
        Histogram bins.
    robust : bool
        Plot the tasks' robust scores (:func:`affordgrasp.robust.ranking_column`) instead.
    stored : sequence of str
        Task probabilities whose ``p_T`` column the rows carry from the models in use
        (:func:`affordgrasp.search.best.stored_probabilities`): read, not computed again.
    progress : callable, optional
        Called with the number of rows after each batch of either pass.

    Returns
    -------
    DatasetSummary
    """
    import pyarrow.compute as pc

    from ..robust import task_scores
    from ..tasks import MetricColumns
    from ..tasks.builtins import probability_value

    thresholds = thresholds or {}
    numeric = _numeric_fields(schema)
    columns = [c for c in ("object", "status", "epsilon_reason") if c in schema.names]
    columns += [c for c in numeric if c not in columns]
    out = DatasetSummary(metrics={name: Summary() for name in numeric})
    for t in tasks:
        out.task_ranges[t.name] = Summary()
        out.affordances[t.name] = {}
        if t.probability:
            out.probable[t.name] = {}
    columns += [f"p_{t}" for t in stored if f"p_{t}" in schema.names and f"p_{t}" not in columns]

    def scores_of(table):
        m = MetricColumns(table)
        return {
            t.name: (
                probability_value(
                    t.name, table.column(f"p_{t.name}").to_numpy(zero_copy_only=False), m
                )
                if t.name in stored
                else task_scores(t, m, mode, thresholds.get(t.name), robust=robust)
            )
            for t in tasks
        }

    def codes(table, column):
        # a string column as dictionary codes (no Python object per row; a null reads "None")
        enc = pc.fill_null(table.column(column), "None").combine_chunks().dictionary_encode()
        return enc.indices.to_numpy(zero_copy_only=False), enc.dictionary.to_pylist()

    def counted(table, column):
        # (object, value) -> rows, by numpy on dictionary codes (pyarrow's group_by held on
        # to about 1.4 MB per batch until the end of the pass: 1 GB over 10⁷ rows)
        value, values = codes(table, column)
        if "object" in table.column_names:
            obj, objects = codes(table, "object")
        else:
            obj, objects = np.zeros(len(value), dtype=np.int64), ["all"]
        k = np.bincount(obj * len(values) + value, minlength=len(objects) * len(values))
        return [
            (objects[i // len(values)], values[i % len(values)], int(c))
            for i, c in enumerate(k)
            if c
        ]

    def groups(table):
        if "object" not in table.column_names:
            return [("all", np.ones(table.num_rows, dtype=bool))]
        enc = table.column("object").combine_chunks().dictionary_encode()
        codes = enc.indices.to_numpy(zero_copy_only=False)
        return [(name, codes == i) for i, name in enumerate(enc.dictionary.to_pylist())]

    for table in scan(columns):  # pass 1: counts and ranges
        out.rows += table.num_rows
        if progress is not None:
            progress(table.num_rows)
        for name in numeric:
            out.metrics[name].see(_column(table, name))
        grp = groups(table)
        if "status" in table.column_names:
            for obj, v, c in counted(table, "status"):
                counts = out.status.setdefault(obj, {})
                counts[v] = counts.get(v, 0) + c
        if "epsilon_reason" in table.column_names:
            reason, reasons = codes(table, "epsilon_reason")
            for i, c in enumerate(np.bincount(reason, minlength=len(reasons))):
                if c and reasons[i] and reasons[i] != "None":
                    out.reasons[reasons[i]] = out.reasons.get(reasons[i], 0) + int(c)
        for task, scores in scores_of(table).items():
            out.task_ranges[task].see(scores)
            for obj, sel in grp:
                out.affordances[task].setdefault(obj, Summary()).see(scores[sel])
                if task in out.probable:
                    n = int(np.count_nonzero(scores[sel] >= PROBABLE))
                    out.probable[task][obj] = out.probable[task].get(obj, 0) + n
    for s in out.metrics.values():
        s.fix_bins(bins)
    for task, per_object in out.affordances.items():
        shared = out.task_ranges[task]
        shared.fix_bins(bins)
        for s in per_object.values():
            # One set of bins per task, so objects compare on the same axis.
            s.edges, s.scale, s.linthresh = shared.edges, shared.scale, shared.linthresh
            s.counts = None if shared.edges is None else np.zeros(bins, dtype=np.int64)
    if tasks or numeric:
        for table in scan(columns):  # pass 2: histograms
            if progress is not None:
                progress(table.num_rows)
            for name in numeric:
                out.metrics[name].add(_column(table, name))
            if tasks:
                grp = groups(table)
                for task, scores in scores_of(table).items():
                    for obj, sel in grp:
                        out.affordances[task][obj].add(scores[sel])
    return out


def plot_metric_distributions(summary: DatasetSummary, path: str | os.PathLike) -> Path:
    """One histogram per numeric metric column, with the share of ±inf and NaN.

    Parameters
    ----------
    summary : DatasetSummary
    path : path
        The PNG file.

    Returns
    -------
    pathlib.Path
    """
    names = list(summary.metrics)
    ncols = 4
    nrows = max(1, -(-len(names) // ncols))
    height = 80 + 210 * nrows
    fig = new_figure(1200, height, axes=False)
    fig.suptitle(f"metric distributions ({summary.rows:,} rows)", fontsize=12, y=1 - 12 / height)
    grid = fig.add_gridspec(
        nrows,
        ncols,
        left=0.05,
        right=0.98,
        top=1 - 85 / height,
        bottom=0.04,
        hspace=0.55,
        wspace=0.25,
    )
    for i, name in enumerate(names):
        ax = fig.add_subplot(grid[i // ncols, i % ncols])
        s = summary.metrics[name]
        _draw_hist(ax, s)
        note = s.note()
        ax.set_title(name + (f"\n{note}" if note else ""), fontsize=9)
    return save_figure(fig, path)


def plot_status_counts(summary: DatasetSummary, path: str | os.PathLike) -> Path:
    """Outcome of the grasp policy per object (stacked shares), and why ε = 0.

    Parameters
    ----------
    summary : DatasetSummary
    path : path
        The PNG file.

    Returns
    -------
    pathlib.Path
    """
    objects = sorted(summary.status)
    statuses = [s for s in STATUS_COLORS if any(s in c for c in summary.status.values())]
    statuses += sorted({k for c in summary.status.values() for k in c} - set(statuses))
    has_reasons = bool(summary.reasons)
    height = max(260, 90 + 26 * max(len(objects), len(summary.reasons) if has_reasons else 0))
    fig = new_figure(1200 if has_reasons else 700, height, axes=False)
    fig.suptitle(f"grasp outcomes ({summary.rows:,} rows)", fontsize=12, y=1 - 12 / height)
    box_top = 1 - 75 / height
    box_left, box_width = (0.09, 0.36) if has_reasons else (0.14, 0.62)
    ax = fig.add_axes((box_left, 45 / height, box_width, box_top - 45 / height))
    y = np.arange(len(objects))
    left = np.zeros(len(objects))
    totals = np.array([max(sum(summary.status[o].values()), 1) for o in objects], dtype=np.float64)
    for st in statuses:
        k = np.array([summary.status[o].get(st, 0) for o in objects], dtype=np.float64)
        share = 100.0 * k / totals
        ax.barh(y, share, left=left, color=STATUS_COLORS.get(st, None), label=st, height=0.7)
        for yi, (l0, w, n) in enumerate(zip(left, share, k, strict=True)):
            if w >= 9:
                ax.text(
                    l0 + w / 2,
                    yi,
                    f"{int(n):,}",
                    ha="center",
                    va="center",
                    fontsize=7,
                    color="white",
                )
        left += share
    ax.set_yticks(y, objects, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(0, 100)
    ax.set_xlabel("share of samples (%)", fontsize=9)
    ax.tick_params(labelsize=8)
    ax.legend(
        loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=len(statuses), fontsize=8, frameon=False
    )
    if has_reasons:
        ax2 = fig.add_axes((0.66, 45 / height, 0.32, box_top - 45 / height))
        items = sorted(summary.reasons.items(), key=lambda kv: (-kv[1], kv[0]))[:15]
        labels = [k if len(k) <= 40 else k[:39] + "…" for k, _ in items]
        ax2.barh(np.arange(len(items)), [v for _, v in items], color="#8172b2", height=0.7)
        ax2.set_yticks(np.arange(len(items)), labels, fontsize=7)
        ax2.invert_yaxis()
        ax2.set_title("why ε = 0 (rows)", fontsize=9)
        ax2.tick_params(labelsize=7)
    return save_figure(fig, path)


def plot_affordances(
    summary: DatasetSummary, path: str | os.PathLike, *, mode: str = "default"
) -> Path:
    """Per task, the distribution of finite scores of each object and the share accepted.

    The same bins for all objects; accepted means score > −∞.

    Parameters
    ----------
    summary : DatasetSummary
    path : path
        The PNG file.
    mode : str
        Threshold mode (shown in the title).

    Returns
    -------
    pathlib.Path
    """
    tasks = list(summary.affordances)
    objects = sorted({o for per in summary.affordances.values() for o in per})
    if not tasks:
        raise ValueError("no task to plot")
    row_h = 34
    panel_h = 70 + row_h * max(len(objects), 1)
    height = 40 + panel_h * len(tasks)
    fig = new_figure(1000, height, axes=False)
    fig.suptitle(f"affordance values per object (mode {mode})", fontsize=12, y=1 - 12 / height)
    for i, task in enumerate(tasks):
        top = 40 + i * panel_h
        ax = fig.add_axes((0.16, 1 - (top + panel_h - 40) / height, 0.62, (panel_h - 75) / height))
        shared = summary.task_ranges[task]
        for j, obj in enumerate(objects):
            s = summary.affordances[task].get(obj)
            if s is None or s.counts is None or s.counts.sum() == 0:
                continue
            h = s.counts / s.counts.max() * 0.42
            centers = 0.5 * (s.edges[:-1] + s.edges[1:])
            ax.fill_between(centers, j - h, j + h, step="mid", color="#4c72b0", alpha=0.85, lw=0)
            # The object's best finite score, exactly (bins only approximate it).
            ax.plot(
                [s.hi],
                [j],
                marker="|",
                ms=14,
                mew=2,
                color="#d62728",
                ls="none",
                zorder=3,
                clip_on=False,
            )
        if shared.scale == "log":
            ax.set_xscale("log")
        elif shared.scale == "symlog":
            ax.set_xscale("symlog", linthresh=shared.linthresh)
        if shared.edges is not None:
            ax.set_xlim(shared.edges[0], shared.edges[-1])
        else:
            _say_empty(ax, "no sample has a finite score")
        ax.set_ylim(len(objects) - 0.5, -0.5)
        ax.set_yticks(np.arange(len(objects)), objects, fontsize=8)
        ax.tick_params(labelsize=8)
        ax.set_title(f"{task}", fontsize=10, loc="left")
        ax.set_xlabel("F (finite values; red tick: best of the object)", fontsize=8)
        for j, obj in enumerate(objects):
            s = summary.affordances[task].get(obj)
            if s is None:
                continue
            ok = summary.accepted(task, obj)
            said = "with p >= 0.5" if task in summary.probable else "accepted"
            ax.annotate(
                f"{ok:,}/{s.n:,} {said} ({100.0 * ok / max(s.n, 1):.1f}%)",
                xy=(1.01, j),
                xycoords=("axes fraction", "data"),
                va="center",
                fontsize=8,
            )
    return save_figure(fig, path)


def save_plots(
    summary: DatasetSummary, out_dir: str | os.PathLike, *, mode: str = "default"
) -> dict[str, Path]:
    """Write metrics.png, status.png and (with tasks) affordances.png.

    Parameters
    ----------
    summary : DatasetSummary
    out_dir : path
    mode : str
        Threshold mode (shown in the titles).

    Returns
    -------
    dict of str to pathlib.Path
        Plot name -> path written.
    """
    out_dir = Path(out_dir)
    files = {
        "metrics": plot_metric_distributions(summary, out_dir / "metrics.png"),
        "status": plot_status_counts(summary, out_dir / "status.png"),
    }
    if summary.affordances:
        files["affordances"] = plot_affordances(summary, out_dir / "affordances.png", mode=mode)
    return files
