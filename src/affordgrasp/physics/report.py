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
rows are left out of the pair they concern. The statistics live in :mod:`affordgrasp.stats`.

The headline (``report["headline"]``): the AUC for ``hold_ok`` with a bootstrap 95 %
interval of the plain, graded, robust (when the dataset has ``robust_*`` columns) and
settled predictors (``HEADLINE``), overall, per family and among force-closure grasps
(ε > 0). Beside it: the initial penetration distribution, the hold rate per
initial-penetration bin and per number of coupled joints that started at their limit, and
how many force-closure grasps the squeeze ejected.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pyarrow as pa

from ..columns import HOLD_EFFORT_COLUMNS, hold_directions, hold_effort_sum
from ..runtime.writing import atomic_write
from ..stats import bootstrap_auc, roc_auc, roc_curve, spearman

__all__ = ["HEADLINE", "physics_report", "roc_auc", "roc_curve", "spearman"]

# The predictors of the headline table, larger = better, with what each is.
HEADLINE = {
    "task_pick-paper": "plain pick (−ΣE_h)",
    "task_pick": "p_pick, the learned probability of the pick trial",
    "epsilon": "plain ε",
    "hold_dirs": "graded: load directions with finite E_h",
    "graded_pick": "graded pick: hold_dirs, then −ΣE_h of the finite ones",
    "robust_hold": "robust pick score: graded hold over the perturbed copies",
    "robust_pick-paper": "robust: q-quantile of pick (−ΣE_h) over the perturbed copies",
    "robust_hold_dirs": "robust: mean hold_dirs over the perturbed copies",
    "robust_fc": "robust: fraction in force closure",
    "robust_epsilon": "robust: mean ε",
    "settled_epsilon": "ε on the settled contacts",
    "neg_settled_hold_effort_sum": "−ΣE_h on the settled contacts",
    "settled_hold_dirs": "hold_dirs on the settled contacts",
}
# Initial penetration bins, m (as placed from the dataset row, before the back-off).
PENETRATION_BINS = (0.0, 1e-4, 5e-4, 1e-3, 2e-3, math.inf)

BINARY_OUTCOMES = ("hold_ok", "settled", "impact_ok", "press_held")
GRADED_OUTCOMES = ("hold_directions_ok", "impact_steadiness", "press_force_n")
# The pair each metric was designed for (the headline of the report).
DESIGNED_FOR = {
    "epsilon": "hold_ok",
    "neg_hold_effort_sum": "hold_ok",
    "task_pick-paper": "hold_ok",
    "task_viable": "hold_ok",
    "neg_impact_effort": "impact_ok",
    "task_beat-paper": "impact_ok",
    "use_force": "press_force_n",
    "task_cut-ug": "press_force_n",
}
# The task trials (docs/physics.md): per task, its outcome and the scores judged against it:
# the learned probability, the threshold task that ranked before it, the paper's formula.
TASK_TRIALS = {
    "beat": ("beat_ok", ("beat", "beat-rules", "beat-paper")),
    "cut": ("cut_ok", ("cut", "cut-rules", "cut-ug")),
    "pick": ("pick_ok", ("pick", "pick-paper")),
}


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
    preds["hold_dirs"], finite_sum = hold_directions({c: col(c) for c in HOLD_EFFORT_COLUMNS})
    # Lexicographic: more finite directions first, then the smaller effort over them; the
    # one-copy form of robust_hold (docs/robust.md), so the plain and robust scores compare.
    preds["graded_pick"] = preds["hold_dirs"] - finite_sum / (finite_sum + 1.0)
    names = set(table.column_names)
    if "settled_epsilon" in names:
        preds["settled_epsilon"] = col("settled_epsilon")
        preds["neg_settled_hold_effort_sum"] = -col("settled_hold_effort_sum")
        preds["settled_hold_dirs"] = col("settled_hold_dirs")
    for name in sorted(names):
        kind = table.schema.field(name).type
        if name.startswith("robust_") and (pa.types.is_floating(kind) or pa.types.is_integer(kind)):
            preds[name] = col(name)
    # the metrics, and the robust columns that a task probability's robust model reads
    columns = {
        name: col(name)
        for name in table.column_names
        if _is_metric(table, name) or name in preds and name.startswith("robust_")
    }
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
    def col(name):
        return np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=np.float64)

    return {
        "hold_ok": _trial_outcome(table, "hold_ok"),
        "settled": _trial_outcome(table, "settled"),
        "impact_ok": _trial_outcome(table, "impact_ok"),
        "press_held": _trial_outcome(table, "press_held"),
        "hold_directions_ok": col("hold_directions_ok"),
        "impact_steadiness": -col("impact_angle_rad"),
        "press_force_n": col("press_force_n"),
    }


def _family(name: str) -> str:
    return name.split(":", 1)[0]


def _why_undefined(predictor: str, x: np.ndarray, outcome: str, y: np.ndarray) -> str:
    """Why the AUC or ρ of predictor values ``x`` against outcomes ``y`` is NaN, in words."""
    keep = ~(np.isnan(x) | np.isnan(y))
    x, y = x[keep], y[keep]
    if len(x) < 3:
        return f"{len(x)} rows with both {predictor} and {outcome}"
    if np.all(x == -np.inf):
        return f"every {predictor} is -inf (no grasp passes the task)"
    if np.all(x == x[0]):
        return f"{predictor} is the same on every row"
    return f"{outcome} is the same on every row"


def _stats(preds, outs, mask) -> dict:
    rates: dict[str, float] = {}
    aucs: dict[str, dict[str, float]] = {}
    rhos: dict[str, dict[str, float]] = {}
    undefined: dict[str, dict[str, str]] = {}  # outcome -> predictor -> why it is NaN
    result = {"n": int(mask.sum()), "auc": aucs, "spearman": rhos, "rates": rates}
    for o in BINARY_OUTCOMES:
        y = outs[o][mask]
        valid = ~np.isnan(y)
        rates[o] = float(y[valid].mean()) if valid.any() else math.nan
        aucs[o] = {p: roc_auc(v[mask][valid], y[valid].astype(bool)) for p, v in preds.items()}
    for o in GRADED_OUTCOMES:
        rhos[o] = {p: spearman(v[mask], outs[o][mask]) for p, v in preds.items()}
    for o, values in (*aucs.items(), *rhos.items()):
        for p, value in values.items():
            if math.isnan(value):
                undefined.setdefault(o, {})[p] = _why_undefined(p, preds[p][mask], o, outs[o][mask])
    result["undefined"] = undefined
    return result


def physics_report(
    outcomes: pa.Table,
    directory: str | os.PathLike | None = None,
    *,
    n_boot: int = 1000,
    seed: int = 0,
    compare: Sequence[pa.Table] = (),
) -> dict:
    """AUC and Spearman of every predictor against every outcome, overall and per family.

    Parameters
    ----------
    outcomes : pyarrow.Table
        The table of :func:`affordgrasp.physics.run.read_outcomes`.
    directory : path, optional
        If given, write report.json, report.md and PNG plots there.
    n_boot : int
        Bootstrap resamples of the headline intervals.
    seed : int
        Seed of the bootstrap (same seed, same report).
    compare : sequence of pyarrow.Table
        Outcomes of other runs (e.g. the other protocol): their headline over all rows is
        reported beside this run's (``report["by_run"]``); the other tables are this run's.

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
    names = set(outcomes.column_names)
    if "protocol" in names:
        report["protocol"] = sorted(set(outcomes.column("protocol").to_pylist()))
    if compare:
        runs = {}
        for k, table in enumerate([outcomes, *compare]):
            name = f"run {k}"
            if "protocol" in table.column_names:
                name = "+".join(sorted(set(table.column("protocol").to_pylist()))) or name
            every = np.ones(table.num_rows, dtype=bool)
            runs[name if name not in runs else f"{name} ({k})"] = _headline(
                _predictors(table), _outcomes(table), every, n_boot, seed
            )
        report["by_run"] = runs
    fc = preds["epsilon"] > 0
    report["headline"] = {
        "outcome": "hold_ok",
        "predictors": {k: v for k, v in HEADLINE.items() if k in preds},
        "all": _headline(preds, outs, np.ones(len(families), dtype=bool), n_boot, seed),
        "families": {
            f: _headline(preds, outs, families == f, n_boot, seed) for f in sorted(set(families))
        },
        "force_closure": _headline(preds, outs, fc, n_boot, seed),
        "settled": _headline(preds, outs, settled, n_boot, seed),
        "force_closure_families": {
            f: _headline(preds, outs, fc & (families == f), n_boot, seed)
            for f in sorted(set(families))
        },
    }
    if "initial_penetration_m" in names:
        report["start"] = _start_report(outcomes, outs, fc)
    trials = _task_trials(outcomes, preds, families, n_boot, seed)
    if trials:
        report["task_trials"] = trials
    if directory is not None:
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        from ..jsonable import to_jsonable

        atomic_write(directory / "report.json", json.dumps(to_jsonable(report), indent=2).encode())
        atomic_write(directory / "report.md", report_markdown(report).encode())
        _plots(preds, outs, families, report, directory)
        if trials:
            _calibration_plot(outcomes, preds, directory)
    return report


def _trial_outcome(table: pa.Table, name: str) -> np.ndarray:
    """A nullable boolean outcome column as 1.0 / 0.0, NaN where null (not tried)."""
    return np.array([math.nan if v is None else float(v) for v in table.column(name).to_pylist()])


def _task_trials(table: pa.Table, preds, families, n_boot: int, seed: int) -> dict:
    """Per task trial run, overall and per family: the rate, and the AUC [bootstrap 95 %] of
    p_T, of the threshold task and of the paper's formula against T_ok; p_T's ECE."""
    from ..stats import expected_calibration_error

    out = {}
    for task, (label, scores) in TASK_TRIALS.items():
        if label not in table.column_names:
            continue
        y = _trial_outcome(table, label)
        tried = ~np.isnan(y)
        if not tried.any():
            continue
        groups = {"all": tried} | {f: tried & (families == f) for f in sorted(set(families[tried]))}
        section = {}
        for group, mask in groups.items():
            yy = y[mask].astype(bool)
            entry = {"n": int(mask.sum()), "rate": float(yy.mean()), "auc": {}}
            for name in scores:
                x = preds.get(f"task_{name}")
                if x is not None:
                    entry["auc"][name] = list(bootstrap_auc(x[mask], yy, n_boot=n_boot, seed=seed))
            p = preds.get(f"task_{task}")
            if p is not None:
                entry["ece"] = expected_calibration_error(yy, np.clip(p[mask], 0.0, 1.0))
            section[group] = entry
        out[task] = {"outcome": label, "scores": list(scores), "groups": section}
    return out


def _task_trials_markdown(trials: dict) -> list[str]:
    lines = []
    for task, t in trials.items():
        scores = t["scores"]
        lines += [
            f"## Task trial `{t['outcome']}`: ROC-AUC [bootstrap 95 % interval]",
            "",
            "| rows | n | success rate | "
            + " | ".join(f"`{s}`" for s in scores)
            + f" | ECE of p_{task} |",
            "|---|---:|---:|" + "---|" * len(scores) + "---:|",
        ]
        for group, g in t["groups"].items():
            cells = [_ci(g["auc"][s]) if s in g["auc"] else "—" for s in scores]
            ece = _f(g["ece"]) if "ece" in g else "—"
            lines.append(
                f"| {group} | {g['n']} | {g['rate']:.3f} | " + " | ".join(cells) + f" | {ece} |"
            )
        lines.append("")
    return lines


def _calibration_plot(table: pa.Table, preds, directory: Path) -> None:
    """Observed success rate against p_T (ten bins) for each task trial run."""
    from ..stats import reliability_bins

    fig = _figure(figsize=(5, 4.5))
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1], color="0.6", linewidth=1, linestyle="--", label="perfect")
    for task, (label, _) in TASK_TRIALS.items():
        p = preds.get(f"task_{task}")
        if label not in table.column_names or p is None:
            continue
        y = _trial_outcome(table, label)
        tried = ~np.isnan(y)
        if not tried.any():
            continue
        b = reliability_bins(y[tried], np.clip(p[tried], 0.0, 1.0))
        ok = b["count"] > 0
        ax.plot(b["mean_probability"][ok], b["positive_rate"][ok], marker="o", label=f"p_{task}")
    ax.set_xlabel("predicted probability")
    ax.set_ylabel("observed success rate")
    ax.set_title("Calibration of the task probabilities")
    ax.legend(loc="upper left")
    _save_png(fig, directory / "calibration_tasks.png")


def _save_png(fig, path: Path) -> None:
    """Write a figure as a PNG (110 dpi), atomically."""
    atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=110))


def _headline(preds, outs, mask, n_boot: int, seed: int) -> dict:
    """n, hold rate and {predictor: [AUC, low, high]} for ``hold_ok`` among ``mask``."""
    y = outs["hold_ok"][mask]
    valid = ~np.isnan(y)
    label = y[valid].astype(bool)
    aucs = {
        p: list(bootstrap_auc(preds[p][mask][valid], label, n_boot=n_boot, seed=seed))
        for p in HEADLINE
        if p in preds
    }
    rate = float(label.mean()) if len(label) else math.nan
    return {"n": int(valid.sum()), "hold_rate": rate, "auc": aucs}


def _rates(outs, ejected, sel) -> dict:
    n = int(sel.sum())
    if n == 0:
        return {"n": 0, "hold_rate": math.nan, "settled_rate": math.nan, "ejected_rate": math.nan}
    return {
        "n": n,
        "hold_rate": float(np.nanmean(outs["hold_ok"][sel])),
        "settled_rate": float(np.nanmean(outs["settled"][sel])),
        "ejected_rate": float(np.mean(ejected[sel])),
    }


def _start_report(table: pa.Table, outs, fc) -> dict:
    """Initial penetration, back-off, couplings at their limit, ejections."""

    def col(name):
        return np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=np.float64)

    initial, start = col("initial_penetration_m"), col("start_penetration_m")
    ejected = col("ejected") > 0.5
    at_limit = col("distal_at_limit").astype(np.int64)
    quantiles = (0.5, 0.9, 0.99, 1.0)
    bins = []
    for lo, hi in zip(PENETRATION_BINS[:-1], PENETRATION_BINS[1:], strict=True):
        sel = (initial >= lo) & (initial < hi) if lo > 0 else initial < hi
        label = f"{lo * 1e3:g}–{hi * 1e3:g} mm" if math.isfinite(hi) else f"≥ {lo * 1e3:g} mm"
        bins.append({"bin": label, **_rates(outs, ejected, sel)})
    return {
        "n": len(initial),
        "initial_penetration_m": {
            f"q{int(q * 100)}": float(np.quantile(initial, q)) for q in quantiles
        }
        if len(initial)
        else {},
        "start_penetration_m": {f"q{int(q * 100)}": float(np.quantile(start, q)) for q in quantiles}
        if len(start)
        else {},
        "initial_over_0.5mm": float(np.mean(initial >= 5e-4)) if len(initial) else math.nan,
        "start_under_0.5mm": float(np.mean(start < 5e-4)) if len(start) else math.nan,
        "backed_off": float(np.mean(initial > start)) if len(start) else math.nan,
        "by_initial_penetration": bins,
        "by_distal_at_limit": [
            {"count": int(k), **_rates(outs, ejected, at_limit == k)}
            for k in range(int(at_limit.max(initial=0)) + 1)
        ],
        "force_closure": {
            "n": int(fc.sum()),
            "ejected_rate": _rates(outs, ejected, fc)["ejected_rate"],
        },
        "ejected_rate": float(np.mean(ejected)) if len(ejected) else math.nan,
    }


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
    if "protocol" in report:
        lines += [f"Protocol: {', '.join(report['protocol'])} (docs/physics.md).", ""]
    if "by_run" in report:
        lines += _runs_markdown(report["by_run"], report["headline"]["predictors"])
    if "headline" in report:
        lines += _headline_markdown(report["headline"])
    if "task_trials" in report:
        lines += _task_trials_markdown(report["task_trials"])
    if "start" in report:
        lines += _start_markdown(report["start"])
    lines += _markdown_block(report, "")
    if "settled" in report:
        lines += ["", "# Among the grasps that settled after the squeeze", ""]
        lines += _markdown_block(report["settled"], "#")
    return "\n".join(lines) + "\n"


def _ci(v) -> str:
    auc, lo, hi = v
    return "—" if math.isnan(auc) else f"{auc:.3f} [{_f(lo)}–{_f(hi)}]"


def _headline_markdown(h: dict) -> list[str]:
    lines = []
    for title, overall, fams in (
        ("all grasps", h["all"], h["families"]),
        ("force-closure grasps (ε > 0)", h["force_closure"], h["force_closure_families"]),
        ("grasps that settled after the squeeze", h["settled"], {}),
    ):
        groups = [("all", overall)] + list(fams.items())
        lines += [
            f"## ROC-AUC for `hold_ok` [bootstrap 95 % interval], {title}",
            "",
            "| predictor | " + " | ".join(f"{g} (n={v['n']})" for g, v in groups) + " |",
            "|---" * (1 + len(groups)) + "|",
            "| hold rate | " + " | ".join(_f(v["hold_rate"]) for _, v in groups) + " |",
        ]
        for p in h["predictors"]:
            lines.append(f"| {p} | " + " | ".join(_ci(v["auc"][p]) for _, v in groups) + " |")
        lines.append("")
    lines += ["Predictors: " + "; ".join(f"`{k}` {v}" for k, v in h["predictors"].items()), ""]
    return lines


def _runs_markdown(by: dict, predictors: dict) -> list[str]:
    groups = list(by.items())
    lines = [
        "## ROC-AUC for `hold_ok` per run [bootstrap 95 % interval]",
        "",
        "| predictor | " + " | ".join(f"{p} (n={v['n']})" for p, v in groups) + " |",
        "|---" * (1 + len(groups)) + "|",
        "| hold rate | " + " | ".join(_f(v["hold_rate"]) for _, v in groups) + " |",
    ]
    for p in predictors:
        cells = [_ci(v["auc"][p]) if p in v["auc"] else "—" for _, v in groups]
        lines.append(f"| {p} | " + " | ".join(cells) + " |")
    return lines + [""]


def _start_markdown(st: dict) -> list[str]:
    def mm(d):
        return ", ".join(f"{k} {v * 1e3:.3f}" for k, v in d.items())

    lines = [
        "## The start of the replay",
        "",
        f"* initial penetration as placed (mm): {mm(st['initial_penetration_m'])}; "
        f"{100 * st['initial_over_0.5mm']:.1f} % of rows at 0.5 mm or deeper",
        f"* at the start of the squeeze, after the back-off (mm): "
        f"{mm(st['start_penetration_m'])}; {100 * st['start_under_0.5mm']:.1f} % of rows "
        "below 0.5 mm",
        f"* the squeeze left no contact (ejected): {100 * st['ejected_rate']:.1f} % of all rows, "
        f"{100 * st['force_closure']['ejected_rate']:.1f} % of the "
        f"{st['force_closure']['n']} force-closure rows",
        "",
        "| initial penetration | n | hold | settled | ejected |",
        "|---|---|---|---|---|",
    ]
    for b in st["by_initial_penetration"]:
        lines.append(
            f"| {b['bin']} | {b['n']} | {_f(b['hold_rate'])} | {_f(b['settled_rate'])} | "
            f"{_f(b['ejected_rate'])} |"
        )
    lines += ["", "| coupled joints at their limit | n | hold | settled | ejected |"]
    lines.append("|---|---|---|---|---|")
    for b in st["by_distal_at_limit"]:
        lines.append(
            f"| {b['count']} | {b['n']} | {_f(b['hold_rate'])} | {_f(b['settled_rate'])} | "
            f"{_f(b['ejected_rate'])} |"
        )
    return lines + [""]


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


def _figure(**kwargs):
    """A matplotlib Figure not attached to pyplot (the caller's backend stays as it is)."""
    from matplotlib.figure import Figure

    return Figure(**kwargs)


def _plots(preds, outs, families, report, directory: Path) -> None:
    _headline_roc(preds, outs, families, report, directory)

    for outcome, names in (
        ("hold_ok", ["epsilon", "neg_hold_effort_sum", "task_pick", "task_viable"]),
        ("impact_ok", ["neg_impact_effort", "task_beat-paper", "discharge", "epsilon"]),
        ("press_held", ["use_force", "task_cut-ug", "epsilon"]),
    ):
        y = outs[outcome]
        valid = ~np.isnan(y)
        fig = _figure(figsize=(5, 5))
        ax = fig.subplots()
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
        _save_png(fig, directory / f"roc_{outcome}.png")

    fams = sorted(report["families"])
    names = ["epsilon", "neg_hold_effort_sum", "task_pick", "task_viable"]
    fig = _figure(figsize=(max(6, 1.2 * len(fams)), 4))
    ax = fig.subplots()
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
    _save_png(fig, directory / "auc_hold_by_family.png")

    _why_plot(preds, outs, directory)

    fig = _figure(figsize=(10, 4))
    axes = fig.subplots(1, 2)
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
    _save_png(fig, directory / "scatter.png")


def _headline_roc(preds, outs, families, report, directory: Path) -> None:
    """ROC curves of the headline predictors for ``hold_ok``: all rows, then per family."""
    fams = ["all", *sorted(report["families"])]
    cols = min(4, len(fams))
    rows = -(-len(fams) // cols)
    fig = _figure(figsize=(4 * cols, 4 * rows))
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    y = outs["hold_ok"]
    for ax, fam in zip(axes, fams, strict=False):
        sel = ~np.isnan(y) if fam == "all" else ~np.isnan(y) & (families == fam)
        h = report["headline"]["all" if fam == "all" else "families"]
        h = h if fam == "all" else h[fam]
        for p in report["headline"]["predictors"]:
            fpr, tpr = roc_curve(preds[p][sel], y[sel].astype(bool))
            ax.plot(fpr, tpr, linewidth=1, label=f"{p} {_ci(h['auc'][p])}")
        ax.plot([0, 1], [0, 1], color="0.7", linestyle="--", linewidth=1)
        ax.set_title(f"{fam} (n={int(sel.sum())})", fontsize=9)
        ax.set_xlabel("false positive rate", fontsize=8)
        ax.set_ylabel("true positive rate", fontsize=8)
        ax.legend(loc="lower right", fontsize=5)
    for ax in axes[len(fams) :]:
        ax.set_visible(False)
    fig.tight_layout()
    _save_png(fig, directory / "roc_hold_headline.png")


def _why_plot(preds, outs, directory: Path) -> None:
    """Outcome rates per ε bin: where the hold test's successes and failures sit."""
    eps = preds["epsilon"]
    positive = eps[eps > 0]
    edges = np.quantile(positive, [0.0, 0.25, 0.5, 0.75, 1.0]) if len(positive) else []
    bins = [("ε = 0", eps <= 0)]
    for lo, hi in zip(edges[:-1], edges[1:], strict=False):
        bins.append((f"{lo:.3g}–{hi:.3g}", (eps > 0) & (eps >= lo) & (eps <= hi)))
    fig = _figure(figsize=(8, 4))
    ax = fig.subplots()
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
    _save_png(fig, directory / "why_epsilon_bins.png")
