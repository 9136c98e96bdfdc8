"""Do the metrics predict what the physics engine sees? ROC-AUC and Spearman, per family.

Predictors are oriented so that larger means "better grasp": ε, −ΣE_h, −E_i, U_τ, δ and
every registered task's score in its default mode and without the robustness threshold
(``task_NAME@no-robustness``); −∞ when a threshold fails. Outcomes:

* binary: ``hold_ok`` (settled and all six hold directions), ``settled`` (the object came
  to rest in the hand after the squeeze), ``impact_ok``, ``press_held``;
* graded: ``hold_directions_ok`` (0..6), ``-impact_angle_rad``, ``press_force_n``.

ROC-AUC is the Mann–Whitney probability that a random success outranks a random failure,
ties counted one half (so a predictor that is −∞ or 0 for most rows gets no credit for
them); it is undefined (NaN) when a group has only successes or only failures. Spearman's
ρ is the Pearson correlation of average ranks. ±∞ rank as the largest/smallest values; NaN
rows are left out of the pair they concern.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pyarrow as pa
from scipy.stats import rankdata

from ..columns import HOLD_EFFORT_COLUMNS, hold_effort_sum

__all__ = ["physics_report", "roc_auc", "roc_curve", "spearman"]

BINARY_OUTCOMES = ("hold_ok", "settled", "impact_ok", "press_held")
GRADED_OUTCOMES = ("hold_directions_ok", "impact_steadiness", "press_force_n")
# The pair each metric was designed for (the headline of the report).
DESIGNED_FOR = {
    "epsilon": "hold_ok",
    "neg_hold_effort_sum": "hold_ok",
    "task_pick": "hold_ok",
    "task_viable": "hold_ok",
    "neg_impact_effort": "impact_ok",
    "task_beat": "impact_ok",
    "use_force": "press_force_n",
    "task_cut": "press_force_n",
}


def roc_auc(score: np.ndarray, label: np.ndarray) -> float:
    """ROC-AUC of ``score`` for binary ``label`` (ties count 1/2); NaN if one class is empty.

    Parameters
    ----------
    score : (n,) float ndarray
        Larger = more likely positive (±inf allowed, NaN rows dropped).
    label : (n,) bool ndarray

    Returns
    -------
    float
    """
    score = np.asarray(score, dtype=np.float64)
    label = np.asarray(label, dtype=bool)
    keep = ~np.isnan(score)
    score, label = score[keep], label[keep]
    n_pos, n_neg = int(label.sum()), int((~label).sum())
    if n_pos == 0 or n_neg == 0:
        return math.nan
    ranks = rankdata(score)  # average ranks: ties count one half
    return float((ranks[label].sum() - n_pos * (n_pos + 1) / 2) / (n_pos * n_neg))


def roc_curve(score: np.ndarray, label: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ROC curve at every distinct threshold, from (0, 0).

    Parameters
    ----------
    score : (n,) float ndarray
    label : (n,) bool ndarray

    Returns
    -------
    fpr, tpr : float64 ndarray
        False and true positive rates.
    """
    score = np.asarray(score, dtype=np.float64)
    label = np.asarray(label, dtype=bool)
    keep = ~np.isnan(score)
    score, label = score[keep], label[keep]
    order = np.argsort(-score, kind="stable")
    s, y = score[order], label[order]
    # The last index of every run of equal scores (±inf compare equal to themselves).
    distinct = np.r_[np.flatnonzero(s[1:] != s[:-1]), len(s) - 1] if len(s) else np.zeros(0, int)
    tp = np.cumsum(y)[distinct]
    fp = np.cumsum(~y)[distinct]
    p, n = max(int(y.sum()), 1), max(int((~y).sum()), 1)
    return np.r_[0.0, fp / n], np.r_[0.0, tp / p]


def spearman(x: np.ndarray, y: np.ndarray) -> float:
    """Spearman's ρ (average ranks; ±inf rank at the ends); NaN pairs dropped.

    Parameters
    ----------
    x, y : (n,) float ndarray

    Returns
    -------
    float
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    keep = ~(np.isnan(x) | np.isnan(y))
    x, y = x[keep], y[keep]
    if len(x) < 3:
        return math.nan
    rx, ry = rankdata(x), rankdata(y)
    if rx.std() == 0 or ry.std() == 0:
        return math.nan
    return float(np.corrcoef(rx, ry)[0, 1])


def _predictors(table: pa.Table) -> dict[str, np.ndarray]:
    from ..tasks import evaluate_task, list_tasks

    def col(name):
        return np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=np.float64)

    hold = hold_effort_sum({c: col(c) for c in HOLD_EFFORT_COLUMNS})
    preds = {
        "epsilon": col("epsilon"),
        "neg_hold_effort_sum": -hold,
        "neg_impact_effort": -col("impact_effort"),
        "use_force": col("use_force"),
        "discharge": col("discharge"),
    }
    columns = {name: col(name) for name in table.column_names if _is_metric(table, name)}
    for task in list_tasks():
        # The default mode, and the mode without the robustness threshold (τ_ε = -inf): the
        # default thresholds may leave no grasp of a run with a finite score.
        for mode, suffix in (("default", ""), ("no-robustness", "@no-robustness")):
            try:
                with np.errstate(invalid="ignore", divide="ignore"):
                    values = evaluate_task(task, columns, mode)
            except Exception:  # noqa: BLE001 - a user task may lack a mode or a column
                continue
            preds[f"task_{task}{suffix}"] = np.asarray(values, dtype=np.float64)
    return preds


def _is_metric(table: pa.Table, name: str) -> bool:
    from .run import REPORTED_METRICS

    return name in REPORTED_METRICS


def _outcomes(table: pa.Table) -> dict[str, np.ndarray]:
    def opt_bool(name):
        values = table.column(name).to_pylist()
        return np.array([math.nan if v is None else float(v) for v in values])

    def col(name):
        return np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=np.float64)

    return {
        "hold_ok": opt_bool("hold_ok"),
        "settled": opt_bool("settled"),
        "impact_ok": opt_bool("impact_ok"),
        "press_held": opt_bool("press_held"),
        "hold_directions_ok": col("hold_directions_ok"),
        "impact_steadiness": -col("impact_angle_rad"),
        "press_force_n": col("press_force_n"),
    }


def _family(name: str) -> str:
    return name.split(":", 1)[0]


def _stats(preds, outs, mask) -> dict:
    rates: dict[str, float] = {}
    aucs: dict[str, dict[str, float]] = {}
    rhos: dict[str, dict[str, float]] = {}
    result = {"n": int(mask.sum()), "auc": aucs, "spearman": rhos, "rates": rates}
    for o in BINARY_OUTCOMES:
        y = outs[o][mask]
        valid = ~np.isnan(y)
        rates[o] = float(y[valid].mean()) if valid.any() else math.nan
        aucs[o] = {p: roc_auc(v[mask][valid], y[valid].astype(bool)) for p, v in preds.items()}
    for o in GRADED_OUTCOMES:
        rhos[o] = {p: spearman(v[mask], outs[o][mask]) for p, v in preds.items()}
    return result


def physics_report(outcomes: pa.Table, directory: str | os.PathLike | None = None) -> dict:
    """AUC and Spearman of every predictor against every outcome, overall and per family.

    Parameters
    ----------
    outcomes : pyarrow.Table
        The table of :func:`affordgrasp.physics.run.read_outcomes`.
    directory : path, optional
        If given, write report.json, report.md and PNG plots there.

    Returns
    -------
    dict
        The report (JSON-ready).
    """
    preds = _predictors(outcomes)
    outs = _outcomes(outcomes)
    families = np.array([_family(n) for n in outcomes.column("object").to_pylist()])
    report = {"all": _stats(preds, outs, np.ones(len(families), dtype=bool)), "families": {}}
    for fam in sorted(set(families)):
        report["families"][fam] = _stats(preds, outs, families == fam)
    # The same, among the grasps that survived the squeeze: does the metric predict the
    # loads once the object is at rest in the hand?
    settled = outs["settled"] == 1.0
    report["settled"] = {"all": _stats(preds, outs, settled), "families": {}}
    for fam in sorted(set(families)):
        report["settled"]["families"][fam] = _stats(preds, outs, settled & (families == fam))
    report["designed_for"] = DESIGNED_FOR
    if directory is not None:
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        from ..jsonable import to_jsonable

        (directory / "report.json").write_text(json.dumps(to_jsonable(report), indent=2))
        (directory / "report.md").write_text(report_markdown(report))
        _plots(preds, outs, families, report, directory)
    return report


def _f(v: float) -> str:
    return "—" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.3f}"


def report_markdown(report: dict) -> str:
    """The report as a Markdown page.

    Parameters
    ----------
    report : dict
        From :func:`physics_report`.

    Returns
    -------
    str
    """
    lines = ["# Physics validation report", ""]
    lines += _markdown_block(report, "")
    if "settled" in report:
        lines += ["", "# Among the grasps that settled after the squeeze", ""]
        lines += _markdown_block(report["settled"], "#")
    return "\n".join(lines) + "\n"


def _markdown_block(report: dict, deeper: str) -> list[str]:
    lines: list[str] = []
    groups = [("all", report["all"])] + list(report["families"].items())
    lines += [
        f"#{deeper}# Outcome rates",
        "",
        "| group | n | " + " | ".join(BINARY_OUTCOMES) + " |",
    ]
    lines.append("|---" * (2 + len(BINARY_OUTCOMES)) + "|")
    for name, g in groups:
        rates = " | ".join(_f(g["rates"][o]) for o in BINARY_OUTCOMES)
        lines.append(f"| {name} | {g['n']} | {rates} |")
    for outcome in BINARY_OUTCOMES:
        preds = list(report["all"]["auc"][outcome])
        lines += [
            "",
            f"#{deeper}# ROC-AUC for `{outcome}`",
            "",
            "| predictor | " + " | ".join(name for name, _ in groups) + " |",
        ]
        lines.append("|---" * (1 + len(groups)) + "|")
        for p in preds:
            lines.append(
                f"| {p} | " + " | ".join(_f(g["auc"][outcome][p]) for _, g in groups) + " |"
            )
    for outcome in GRADED_OUTCOMES:
        preds = list(report["all"]["spearman"][outcome])
        lines += [
            "",
            f"#{deeper}# Spearman ρ with `{outcome}`",
            "",
            "| predictor | " + " | ".join(name for name, _ in groups) + " |",
        ]
        lines.append("|---" * (1 + len(groups)) + "|")
        for p in preds:
            lines.append(
                f"| {p} | " + " | ".join(_f(g["spearman"][outcome][p]) for _, g in groups) + " |"
            )
    return lines


def _plots(preds, outs, families, report, directory: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for outcome, names in (
        ("hold_ok", ["epsilon", "neg_hold_effort_sum", "task_pick", "task_viable"]),
        ("impact_ok", ["neg_impact_effort", "task_beat", "discharge", "epsilon"]),
        ("press_held", ["use_force", "task_cut", "epsilon"]),
    ):
        y = outs[outcome]
        valid = ~np.isnan(y)
        fig, ax = plt.subplots(figsize=(5, 5))
        for p in names:
            if p not in preds:
                continue
            fpr, tpr = roc_curve(preds[p][valid], y[valid].astype(bool))
            auc = report["all"]["auc"][outcome][p]
            ax.plot(fpr, tpr, label=f"{p} (AUC {_f(auc)})")
        ax.plot([0, 1], [0, 1], color="0.7", linestyle="--", linewidth=1)
        ax.set_xlabel("false positive rate")
        ax.set_ylabel("true positive rate")
        ax.set_title(f"ROC, outcome {outcome} (n={int(valid.sum())})")
        ax.legend(loc="lower right", fontsize=8)
        fig.tight_layout()
        fig.savefig(directory / f"roc_{outcome}.png", dpi=110)
        plt.close(fig)

    fams = sorted(report["families"])
    names = ["epsilon", "neg_hold_effort_sum", "task_pick", "task_viable"]
    fig, ax = plt.subplots(figsize=(max(6, 1.2 * len(fams)), 4))
    width = 0.8 / len(names)
    for i, p in enumerate(names):
        vals = [report["families"][f]["auc"]["hold_ok"].get(p, math.nan) for f in fams]
        ax.bar(np.arange(len(fams)) + i * width, np.nan_to_num(vals, nan=0.0), width, label=p)
    ax.axhline(0.5, color="0.5", linewidth=1, linestyle="--")
    ax.axhline(0.85, color="tab:red", linewidth=1, linestyle=":")
    ax.set_xticks(np.arange(len(fams)) + 0.4 - width / 2, fams)
    ax.set_ylim(0, 1)
    ax.set_ylabel("ROC-AUC, hold test")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(directory / "auc_hold_by_family.png", dpi=110)
    plt.close(fig)

    _why_plot(preds, outs, directory, plt)

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, (p, o, label) in zip(
        axes,
        (
            ("use_force", "press_force_n", "U_τ (N per 1 N of grip)"),
            ("epsilon", "hold_directions_ok", "ε"),
        ),
        strict=True,
    ):
        x, y = preds[p], outs[o]
        keep = np.isfinite(x) & np.isfinite(y)
        for fam in fams:
            sel = keep & (families == fam)
            ax.scatter(x[sel], y[sel], s=8, alpha=0.6, label=fam)
        rho = report["all"]["spearman"][o][p]
        ax.set_xlabel(label)
        ax.set_ylabel(o)
        ax.set_title(f"Spearman ρ = {_f(rho)}")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(directory / "scatter.png", dpi=110)
    plt.close(fig)


def _why_plot(preds, outs, directory: Path, plt) -> None:
    """Outcome rates per ε bin: where the hold test's successes and failures sit."""
    eps = preds["epsilon"]
    positive = eps[eps > 0]
    edges = np.quantile(positive, [0.0, 0.25, 0.5, 0.75, 1.0]) if len(positive) else []
    bins = [("ε = 0", eps <= 0)]
    for lo, hi in zip(edges[:-1], edges[1:], strict=False):
        bins.append((f"{lo:.3g}–{hi:.3g}", (eps > 0) & (eps >= lo) & (eps <= hi)))
    fig, ax = plt.subplots(figsize=(8, 4))
    x = np.arange(len(bins))
    for i, outcome in enumerate(("settled", "hold_ok")):
        rates = [float(np.nanmean(outs[outcome][sel])) if sel.any() else 0.0 for _, sel in bins]
        ax.bar(x + 0.4 * i, rates, 0.4, label=outcome)
    for k, (_, sel) in enumerate(bins):
        ax.text(x[k] + 0.2, 1.02, f"n={int(sel.sum())}", ha="center", fontsize=8)
    ax.set_xticks(x + 0.2, [name for name, _ in bins], fontsize=8)
    ax.set_ylim(0, 1.1)
    ax.set_xlabel("ε (force closure quartiles)")
    ax.set_ylabel("rate")
    ax.set_title("Outcomes per ε bin: ties at ε = 0 cap the AUC")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(directory / "why_epsilon_bins.png", dpi=110)
    plt.close(fig)
