"""Fit the learned scorer of ``plan --model learned`` and write it with its card.

    python tools/fit_scorer.py --fit DIR --validation DIR [--test DIR]
        [--out src/affordgrasp/learning/pretrained] [--design grid|pointnet] [--epochs 4]

``--fit``, ``--validation`` and ``--test`` hold the files of ``tools/scorer_data.py``, each of
other objects: the validation objects fit the calibration map (and choose a network's
epoch), nothing else; the test objects are only measured. The label is the simulator's:
whether the candidate's grasp is viable on the true object. Two designs:

* ``grid`` (shipped): scikit-learn's HistGradientBoosting on the counts of the hand's volume
  and the features of :func:`affordgrasp.learning.scorer.hand_frame_inputs`, calibrated by
  isotonic regression on the validation objects, exported as a
  :class:`~affordgrasp.tasks.probability.TaskModel`;
* ``pointnet``: the slim PointNet of :mod:`affordgrasp.learning.models` on the points of the
  same volume and the same features (needs PyTorch): the network it was measured against.

Printed per set of objects: pooled ROC-AUC, AUC within objects, ECE, and the decisions: per
object, the first of ``plan``'s candidates by the score (among the first 64 and all 256),
alone and with its first 4, 8 or 16 simulated on the fused surface (viable there first, then
the widest ε there: ``plan --model learned --verify N``), beside the views decider's ranking
of every candidate on the fused surface (the same rule on all of them), random (the mean)
and the oracle; and the CPU time of scoring 64 candidates.
"""

from __future__ import annotations

import argparse
import dataclasses
import glob
import json
import sys
import time
from pathlib import Path

import numpy as np

from affordgrasp.learning.scorer import (
    CLOUD_POINTS,
    COLUMNS,
    INPUT,
    N_FEATURES,
    SCORER_FILE,
    hand_frame_inputs,
)
from affordgrasp.stats import expected_calibration_error, roc_auc

sys.path.insert(0, str(Path(__file__).parent))
from fit_task_probabilities import export, isotonic_knots  # noqa: E402

VERIFY = (4, 8, 16)  # the scorer's first N simulated on the fused surface


def load(folder: str, with_points: bool) -> list[dict]:
    out = []
    for f in sorted(glob.glob(str(Path(folder) / "*.npz"))):
        d = np.load(f)
        # the files keep a larger seeded subset in a seeded order: its first CLOUD_POINTS
        # are a seeded subset of that size, as fused_cloud draws at run time
        inputs = hand_frame_inputs(
            d["cloud"][:CLOUD_POINTS], d["starts"], d["p0"][:, 5], with_points=with_points
        )
        out.append(
            {
                "spec": str(d["spec"]),
                "x": np.concatenate(inputs[:2], axis=1),
                "points": inputs[2] if with_points else None,
                "features": inputs[1],
                "label": d["true_viable"].astype(np.float32),
                "fused_viable": d["fused_viable"],
                "fused_epsilon": np.nan_to_num(d["fused_epsilon"]),
            }
        )
    return out


def decisions(objs, scores) -> dict:
    out: dict = {}
    within = []
    for k in (64, 256):
        rows: dict = {"chosen": [], "views": [], "random": [], "oracle": []}
        rows.update({f"verified_{v}": [] for v in VERIFY})
        for o, s in zip(objs, scores, strict=True):
            y, sk = o["label"][:k] > 0.5, np.asarray(s)[:k]
            fv, fe = o["fused_viable"][:k], o["fused_epsilon"][:k]
            order = np.argsort(-sk, kind="stable")
            rows["chosen"].append(y[order[0]])
            rows["views"].append(y[np.lexsort((-fe, ~fv))[0]])
            rows["random"].append(y.mean())
            rows["oracle"].append(y.any())
            for v in VERIFY:
                top = order[:v]
                rows[f"verified_{v}"].append(y[top[np.lexsort((-fe[top], ~fv[top]))[0]]])
        out.update({f"{key}_{k}": float(np.mean(v)) for key, v in rows.items()})
    for o, s in zip(objs, scores, strict=True):
        y = o["label"] > 0.5
        if 0 < y.sum() < len(y):
            within.append(roc_auc(np.asarray(s), y))
    labels = np.concatenate([o["label"] for o in objs]) > 0.5
    out["auc"] = roc_auc(np.concatenate(scores), labels)
    out["auc_within"] = float(np.mean(within))
    out["objects"] = len(objs)
    return out


def fit_grid(fit, val):
    from sklearn.ensemble import HistGradientBoostingClassifier

    x = np.concatenate([o["x"] for o in fit]).astype(np.float64)
    y = np.concatenate([o["label"] for o in fit])
    t0 = time.process_time()
    clf = HistGradientBoostingClassifier(
        max_iter=300, learning_rate=0.1, max_leaf_nodes=31, random_state=0
    ).fit(x, y)
    print(f"grid: fitted in {time.process_time() - t0:.0f} s CPU", flush=True)
    vx = np.concatenate([o["x"] for o in val]).astype(np.float64)
    vy = np.concatenate([o["label"] for o in val])
    knots = isotonic_knots(clf.decision_function(vx), vy)
    model = export(
        clf, "hist_gradient_boosting", "pick", False, COLUMNS, ("raw",) * len(COLUMNS), knots, {}
    )
    return model, lambda o: model.raw_score(o["x"].astype(np.float64))


def fit_pointnet(fit, val, epochs: int, seed: int):
    import torch

    from affordgrasp.learning.models import build_model

    torch.manual_seed(seed)
    config = {"arch": "pointnet-slim", "width": 16, "dropout": 0.2, "n_pose": N_FEATURES}
    model = build_model(config)
    pts = torch.from_numpy(np.concatenate([o["points"] for o in fit]))
    fea = torch.from_numpy(np.concatenate([o["features"] for o in fit]))
    lab = torch.from_numpy(np.concatenate([o["label"] for o in fit]))
    loss_fn = torch.nn.BCEWithLogitsLoss()
    opt = torch.optim.Adam(model.parameters(), lr=2e-3, weight_decay=1e-5)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, T_max=epochs)
    rng = np.random.default_rng(seed)

    def predict(o):
        model.eval()
        with torch.no_grad():
            return model(torch.from_numpy(o["points"]), torch.from_numpy(o["features"])).numpy()

    best: tuple = (-1.0, None)
    for epoch in range(epochs):
        model.train()
        order = torch.from_numpy(rng.permutation(len(lab)))
        t0 = time.process_time()
        for i in range(0, len(order), 256):
            b = order[i : i + 256]
            opt.zero_grad()
            loss_fn(model(pts[b], fea[b]), lab[b]).backward()
            opt.step()
        sched.step()
        v = decisions(val, [predict(o) for o in val])
        print(
            f"pointnet epoch {epoch} ({time.process_time() - t0:.0f} s CPU): validation AUC "
            f"{v['auc']:.3f}, within {v['auc_within']:.3f}, chosen viable {v['chosen_256']:.3f}",
            flush=True,
        )
        if v["auc_within"] > best[0]:
            best = (v["auc_within"], {k: t.clone() for k, t in model.state_dict().items()})
    model.load_state_dict(best[1])
    vy = np.concatenate([o["label"] for o in val])
    knots = isotonic_knots(np.concatenate([predict(o) for o in val]).astype(np.float64), vy)
    return knots, predict


def scoring_cpu(model) -> float:
    """CPU seconds of scoring 64 candidates of a built-in object's fused views."""
    from affordgrasp.grasp.pregrasp import sample_inputs
    from affordgrasp.learning.plan import OFFSET_RANGE, candidate_views
    from affordgrasp.learning.scorer import score_candidates
    from affordgrasp.objects import load_object

    p0, _ = sample_inputs(0, 0, 64)
    p0[:, 3:5] *= OFFSET_RANGE
    fused = candidate_views(load_object("mug:3"), p0).fuse()
    score_candidates(model, fused, p0)  # the surface's samples, cached per object
    t0 = time.process_time()
    for _ in range(20):
        score_candidates(model, fused, p0)
    return (time.process_time() - t0) / 20


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fit", required=True)
    p.add_argument("--validation", required=True)
    p.add_argument("--test", default=None)
    p.add_argument("--out", default=None, help="write the scorer (grid design) here")
    p.add_argument("--design", choices=("grid", "pointnet"), default="grid")
    p.add_argument("--epochs", type=int, default=4, help="pointnet: passes over the rows")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args()
    points = args.design == "pointnet"
    fit, val = load(args.fit, points), load(args.validation, points)
    test = load(args.test, points) if args.test else []
    print(f"fit {len(fit)} objects, validation {len(val)}, test {len(test)}", flush=True)
    if points:
        knots, raw = fit_pointnet(fit, val, args.epochs, args.seed)
        model = None
    else:
        model, raw = fit_grid(fit, val)
        knots = (model.knots_x, model.knots_y)
    report: dict = {}
    for name, objs in (("validation", val), ("test", test)):
        if objs:
            s = [raw(o) for o in objs]
            report[name] = decisions(objs, s)
            prob = np.interp(np.concatenate(s), *knots)
            labels = np.concatenate([o["label"] for o in objs])
            report[name]["ece"] = expected_calibration_error(labels, prob)
            print(name, json.dumps(report[name], indent=1), flush=True)
    if model is None:
        return
    report["cpu_ms_per_64"] = 1000 * scoring_cpu(model)
    print(f"scoring 64 candidates: {report['cpu_ms_per_64']:.1f} ms CPU", flush=True)
    if args.out:
        card = {
            "input": INPUT,
            "label": "viable on the true object (the simulator's label), task pick",
            "model": "scikit-learn HistGradientBoosting, 300 trees of 31 leaves, isotonic map",
            "data": "tools/scorer_data.py: plan's 256 candidates per object, views aimed 1 cm "
            "and 5 degrees off, the default sensor model",
            "fit_objects": sorted(o["spec"] for o in fit),
            "validation_objects": sorted(o["spec"] for o in val),
            "test_objects": sorted(o["spec"] for o in test),
            **report,
        }
        out = dataclasses.replace(model, card=card)
        path = Path(args.out) / SCORER_FILE
        path.write_text(json.dumps(out.to_dict()) + "\n")
        print("wrote", path)


if __name__ == "__main__":
    main()
