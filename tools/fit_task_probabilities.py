"""Fit the shipped task probabilities p_beat, p_cut, p_pick from task-trial outcomes.

    python tools/fit_task_probabilities.py TRIALS_DIR [TRIALS_DIR ...] --out DIR \
        [--tasks beat,cut,pick] [--holdout-families axe,dagger] [--holdout-seeds 5,6]

TRIALS_DIR: outputs of ``affordgrasp physics DATA --trials beat,cut,pick`` (their rows carry
the dataset's metric columns, robust columns when the dataset had them, and ``beat_ok``,
``cut_ok``, ``pick_ok``). Objects are split by spec: a row is held out when its family is in
``--holdout-families`` or its variant seed in ``--holdout-seeds`` (crisp and ``~scan`` alike);
the rest is the fitting set. Three model classes are compared on the fitting set by
object-grouped cross-validation (log-loss; each candidate's out-of-fold scores): logistic
regression, scikit-learn's histogram gradient boosting and LightGBM, the boosted ones with
monotone constraints where the physics gives a sign. The winner is refitted on the whole
fitting set, calibrated by isotonic regression on its out-of-fold scores, and judged once on
the held-out rows (AUC with a bootstrap 95 % interval, ECE). Deterministic (seed 0). Needs
scikit-learn and lightgbm (not run-time dependencies: the shipped models are JSON that
:mod:`affordgrasp.tasks.probability` evaluates with numpy).
"""

from __future__ import annotations

import argparse
import json
import re
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from affordgrasp.stats import bootstrap_auc, expected_calibration_error, roc_auc
from affordgrasp.tasks.metric_columns import MetricColumns
from affordgrasp.tasks.probability import (
    MODEL_COLUMNS,
    PICK_COLUMNS,
    ROBUST_COLUMNS,
    TaskModel,
    transform_column,
)

EFFORTS = {c for c in MODEL_COLUMNS if c.startswith("hold_effort") or c == "impact_effort"}
# +1: more of it never makes the trial less likely to succeed (efforts read as 1/(1+E)).
INCREASING = {"epsilon", "epsilon_hand", "hold_dirs", *EFFORTS, *ROBUST_COLUMNS}
# and per task: the force the grasp can transmit to the edge
INCREASING_FOR = {"cut": {"use_force"}}


def columns_of(task: str, robust: bool) -> tuple[tuple[str, ...], tuple[str, ...]]:
    cols = (PICK_COLUMNS if task == "pick" else MODEL_COLUMNS) + (ROBUST_COLUMNS if robust else ())
    transforms = tuple("inv1p" if c in EFFORTS else "raw" for c in cols)
    return cols, transforms


def read_trials(paths: list[str]) -> pa.Table:
    tables = []
    for p in paths:
        files = sorted(Path(p).glob("*.parquet")) if Path(p).is_dir() else [Path(p)]
        tables += [pq.read_table(f) for f in files]
    return pa.concat_tables(tables, promote_options="permissive")


_SPEC = re.compile(r"^(?P<family>[a-z_]+)(?::(?P<seed>\d+))?(?P<scan>~scan(?::\d+)?)?")


def split_of(objects: np.ndarray, families: set[str], seeds: set[int]) -> np.ndarray:
    """True where the object is held out."""
    out = np.zeros(len(objects), bool)
    for name in np.unique(objects):
        m = _SPEC.match(str(name))
        family, seed = (m["family"], int(m["seed"] or 0)) if m else (str(name), -1)
        out[objects == name] = family in families or seed in seeds
    return out


def candidates(monotone: list[int]):
    from lightgbm import LGBMClassifier
    from sklearn.ensemble import HistGradientBoostingClassifier
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    return {
        "logistic": lambda: make_pipeline(
            StandardScaler(), LogisticRegression(C=1.0, max_iter=2000)
        ),
        "hist_gradient_boosting": lambda: HistGradientBoostingClassifier(
            max_iter=200,
            learning_rate=0.05,
            max_leaf_nodes=15,
            monotonic_cst=monotone,
            l2_regularization=1.0,
            random_state=0,
        ),
        "lightgbm": lambda: LGBMClassifier(
            n_estimators=200,
            learning_rate=0.05,
            num_leaves=15,
            min_child_samples=20,
            subsample=0.8,
            subsample_freq=1,
            colsample_bytree=0.8,
            reg_lambda=1.0,
            monotone_constraints=monotone,
            random_state=0,
            verbose=-1,
            n_jobs=1,
        ),
    }


def _features_for(kind: str, x: np.ndarray) -> np.ndarray:
    if kind == "logistic":  # no missing values in a linear score: NaN reads as the mean
        return np.nan_to_num(x, nan=0.0, posinf=0.0, neginf=0.0)
    return x


def out_of_fold(make, kind: str, x, y, groups, folds: int = 5) -> np.ndarray:
    from sklearn.model_selection import GroupKFold

    score = np.zeros(len(y))
    for train, test in GroupKFold(n_splits=min(folds, len(np.unique(groups)))).split(x, y, groups):
        model = make().fit(_features_for(kind, x[train]), y[train])
        score[test] = raw_decision(model, kind, _features_for(kind, x[test]))
    return score


def raw_decision(model, kind: str, x: np.ndarray) -> np.ndarray:
    if kind == "lightgbm":
        return model.predict(x, raw_score=True)
    return model.decision_function(x)


def _log_loss(y, p) -> float:
    p = np.clip(p, 1e-6, 1 - 1e-6)
    return float(-np.mean(y * np.log(p) + (1 - y) * np.log(1 - p)))


def isotonic_knots(score: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    from sklearn.isotonic import IsotonicRegression

    iso = IsotonicRegression(out_of_bounds="clip", y_min=0.0, y_max=1.0).fit(score, y)
    return np.asarray(iso.X_thresholds_, float), np.asarray(iso.y_thresholds_, float)


def export(model, kind: str, task: str, robust: bool, cols, transforms, knots, card) -> TaskModel:
    if kind == "logistic":
        scaler, lr = model[0], model[-1]
        arrays = {
            "weights": lr.coef_[0].astype(float),
            "mean": scaler.mean_.astype(float),
            "scale": scaler.scale_.astype(float),
        }
        return TaskModel(
            task, robust, cols, transforms, "linear", arrays, float(lr.intercept_[0]), *knots, card
        )
    nodes: dict[str, list] = {
        k: [] for k in ("feature", "threshold", "left", "right", "nan_left", "value")
    }
    roots = []
    if kind == "lightgbm":
        dump = model.booster_.dump_model()
        bias = 0.0
        for tree in dump["tree_info"]:
            roots.append(_add_lgbm(tree["tree_structure"], nodes))
    else:  # scikit-learn's HistGradientBoosting: a forest of predictor node arrays
        bias = float(np.ravel(model._baseline_prediction)[0])
        for (predictor,) in model._predictors:
            roots.append(_add_hgb(predictor.nodes, nodes, model._bin_mapper))
    arrays = {k: np.asarray(v) for k, v in nodes.items()}
    arrays["roots"] = np.asarray(roots)
    return TaskModel(task, robust, cols, transforms, "trees", arrays, bias, *knots, card)


def _add_lgbm(node: dict, out: dict) -> int:
    i = len(out["feature"])
    for k in out:
        out[k].append(0)
    if "leaf_value" in node:
        out["feature"][i], out["value"][i] = -1, float(node["leaf_value"])
        return i
    if node["decision_type"] != "<=":
        raise ValueError(f"unsupported LightGBM split {node['decision_type']}")
    out["feature"][i] = int(node["split_feature"])
    out["threshold"][i] = float(node["threshold"])
    # LightGBM sends NaN with default_left when its missing type is NaN; otherwise NaN is 0
    missing = node.get("missing_type", "None")
    out["nan_left"][i] = (
        bool(node["default_left"]) if missing == "NaN" else 0.0 <= out["threshold"][i]
    )
    out["left"][i] = _add_lgbm(node["left_child"], out)
    out["right"][i] = _add_lgbm(node["right_child"], out)
    return i


def _add_hgb(nodes, out: dict, _bins) -> int:
    base = len(out["feature"])
    for n in nodes:
        leaf = bool(n["is_leaf"])
        out["feature"].append(-1 if leaf else int(n["feature_idx"]))
        out["threshold"].append(float(n["num_threshold"]))
        out["left"].append(base + int(n["left"]))
        out["right"].append(base + int(n["right"]))
        out["nan_left"].append(bool(n["missing_go_to_left"]))
        out["value"].append(float(n["value"]) if leaf else 0.0)
    return base


def fit_task(table: pa.Table, task: str, robust: bool, held_out: np.ndarray, seed: int = 0):
    label = f"{task}_ok"
    y_all = np.asarray(table.column(label).to_pylist(), dtype=object)
    known = np.array([v is not None for v in y_all])
    cols, transforms = columns_of(task, robust)
    metrics = MetricColumns(table)
    if not all(c in metrics for c in cols):
        return None
    x_all = np.stack(
        [transform_column(metrics[c], t) for c, t in zip(cols, transforms, strict=True)], axis=1
    )
    y_all = np.where(known, y_all, False).astype(float)
    objects = np.asarray(table.column("object").to_pylist())
    fit = known & ~held_out
    test = known & held_out
    x, y, groups = x_all[fit], y_all[fit], objects[fit]
    if len(np.unique(groups)) < 2 or y.min() == y.max():
        print(f"  {task}: too few objects or outcomes to fit ({len(np.unique(groups))} objects)")
        return None
    up = INCREASING | INCREASING_FOR.get(task, set())
    monotone = [1 if c in up else 0 for c in cols]
    results = {}
    for kind, make in candidates(monotone).items():
        t0 = time.process_time()
        oof = out_of_fold(make, kind, x, y, groups)
        knots = isotonic_knots(oof, y)
        p = np.interp(oof, *knots)
        results[kind] = {
            "oof_log_loss": _log_loss(y, p),
            "oof_auc": roc_auc(oof, y.astype(bool)),
            "cpu_s": time.process_time() - t0,
            "oof": oof,
        }
        print(
            f"  {task}{' robust' if robust else ''} {kind}: out-of-fold log-loss "
            f"{results[kind]['oof_log_loss']:.4f} AUC {results[kind]['oof_auc']:.4f}"
        )
    best = min(results, key=lambda k: results[k]["oof_log_loss"])
    model = candidates(monotone)[best]().fit(_features_for(best, x), y)
    knots = isotonic_knots(results[best]["oof"], y)
    card = {
        "task": task,
        "label": label,
        "robust": robust,
        "model_class": best,
        "candidates": {
            k: {kk: round(vv, 4) for kk, vv in v.items() if kk != "oof"} for k, v in results.items()
        },
        "fit_objects": sorted(set(objects[fit].tolist())),
        "fit_rows": int(fit.sum()),
        "fit_positive_rate": float(y.mean()),
    }
    shipped = export(model, best, task, robust, cols, transforms, knots, card)
    if test.any():
        p_test = shipped.predict(MetricColumns(table.filter(pa.array(test))))
        y_test = y_all[test].astype(bool)
        auc, lo, hi = (
            bootstrap_auc(p_test, y_test, seed=seed)
            if y_test.any() and not y_test.all()
            else (float("nan"),) * 3
        )
        card["held_out"] = {
            "objects": sorted(set(objects[test].tolist())),
            "rows": int(test.sum()),
            "positive_rate": float(y_test.mean()),
            "auc": auc,
            "auc_95": [lo, hi],
            "ece": expected_calibration_error(y_test, p_test),
        }
    # the exported model must reproduce the fitted one
    check = shipped.raw_score(x[:200])
    ref = raw_decision(model, best, _features_for(best, x[:200]))
    if not np.allclose(check, ref, atol=1e-6):
        raise SystemExit(f"exported {best} model of {task} differs from the fitted one")
    return shipped


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("trials", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--tasks", default="beat,cut,pick")
    ap.add_argument("--holdout-families", default="")
    ap.add_argument("--holdout-seeds", default="")
    args = ap.parse_args()
    table = read_trials(args.trials)
    fams = {f for f in args.holdout_families.split(",") if f}
    seeds = {int(s) for s in args.holdout_seeds.split(",") if s}
    held_out = split_of(np.asarray(table.column("object").to_pylist()), fams, seeds)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for task in args.tasks.split(","):
        for robust in (False, True):
            model = fit_task(table, task, robust, held_out)
            if model is None:
                continue
            name = f"{task}{'-robust' if robust else ''}.json"
            (out / name).write_text(json.dumps(model.to_dict()), encoding="utf-8")
            print(name, json.dumps({k: v for k, v in model.card.items() if k != "fit_objects"}))


if __name__ == "__main__":
    main()
