"""Calibrate the wedge-angle threshold of the cut task on crisp and scan-like objects.

The wedge angle (``use_wedge_angle``: 2π × the part of a 3 mm ball around U inside the
solid) is meant to hold on real scans, whose edges are rounded and noisy. So the
threshold is chosen on crisp **and** scan-like (``~scan``) variants of the built-in
families, with the labels of ``calibrate_use_edge.py``:

* blade families (knife, meat_cleaver, axe, dagger, sword); the cutting edge is found on
  the crisp mesh (the scan-like one shares its frame); use points from the direction
  mapping, uniform surface samples and samples next to the cutting edge;
* "edge" within 0.5 mm of the cutting edge, "other" farther than 3 mm (flats, spines,
  tips' flanks, handles, guards), and every point of hammer, screwdriver, bottle and mug.
  A scan-like blade's rounded edge lies behind the crisp one (by the median distance R
  from the crisp edge to the scan-like surface, measured per mesh): there the bands are
  R + 0.5 mm and R + 3 mm;
* calibration seeds ``0 .. seeds-1``, held-out seeds ``seeds .. 2 seeds - 1``: the
  threshold maximises the balanced accuracy on the calibration seeds (crisp and scan-like
  pooled), and the held-out seeds are reported apart, per variant.

Run: ``python studies/calibrate_wedge_angle.py [--seeds 2] [--rays 150] [--json]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).parent))
from calibrate_use_edge import (  # noqa: E402
    DOUBLE_EDGED,
    EDGE_DIST_M,
    NON_BLADES,
    OTHER_DIST_M,
    SINGLE_EDGED,
    best_threshold,
    cutting_edges,
    direction_mapping,
    distance_to_segments,
    edge_samples,
)

from affordgrasp.metrics.use_geometry import use_edge_angle, use_wedge_angle  # noqa: E402
from affordgrasp.objects import load_object  # noqa: E402


def collect(seeds: range, rays: int, rng, retreats: list) -> dict:
    """Wedge and dihedral angles (deg) of labelled points, per variant and label."""
    out: dict = {}
    for name in SINGLE_EDGED + DOUBLE_EDGED + NON_BLADES:
        for seed in seeds:
            crisp = load_object(f"{name}:{seed}").mesh
            blade = name not in NON_BLADES
            A, B = cutting_edges(crisp, name in DOUBLE_EDGED) if blade else (np.zeros((0, 3)),) * 2
            for variant, spec in (("crisp", f"{name}:{seed}"), ("scan", f"{name}:{seed}~scan")):
                mesh = load_object(spec).mesh
                P1, T1 = direction_mapping(mesh, rays, rng)
                P2, T2 = trimesh.sample.sample_surface(mesh, rays, seed=int(rng.integers(1 << 31)))
                parts = [(P1, T1), (P2, T2)]
                if blade:
                    parts.append(edge_samples(mesh, A, B, rays // 3, rng))
                P = np.concatenate([p for p, _ in parts])
                T = np.concatenate([t for _, t in parts]).astype(np.int64)
                N = mesh.face_normals[T]
                wedge = np.degrees(use_wedge_angle(mesh, P, N))
                dihedral = np.degrees(use_edge_angle(mesh, P, use_normal=N))
                if blade:
                    dist = distance_to_segments(P, A, B)
                    retreat = 0.0
                    if variant == "scan":
                        t = rng.uniform(0.05, 0.95, 200)
                        seg = rng.integers(0, len(A), 200)
                        on_edge = A[seg] + t[:, None] * (B[seg] - A[seg])
                        crest, _, _ = trimesh.proximity.closest_point(mesh, on_edge)
                        retreat = float(np.median(np.linalg.norm(crest - on_edge, axis=1)))
                        retreats.append(retreat)
                    masks = {
                        "edge": dist <= retreat + EDGE_DIST_M,
                        "other": dist >= retreat + OTHER_DIST_M,
                    }
                else:
                    masks = {"other": np.ones(len(P), dtype=bool)}
                for label, mask in masks.items():
                    slot = out.setdefault((variant, label), {"wedge": [], "dihedral": []})
                    slot["wedge"].append(wedge[mask])
                    slot["dihedral"].append(dihedral[mask])
    return {k: {m: np.concatenate(v[m]) for m in v} for k, v in out.items()}


def accuracy(data: dict, variant: str, metric: str, tau_deg: float) -> dict:
    edge = data[(variant, "edge")][metric]
    other = data[(variant, "other")][metric]
    tpr, tnr = float(np.mean(edge <= tau_deg)), float(np.mean(other > tau_deg))
    return {
        "edge_pass": tpr,
        "other_fail": tnr,
        "balanced_accuracy": 0.5 * (tpr + tnr),
        "n_edge": int(len(edge)),
        "n_other": int(len(other)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2, help="calibration seeds (as many held out)")
    parser.add_argument("--rays", type=int, default=150)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    retreats: list[float] = []
    calib = collect(range(args.seeds), args.rays, rng, retreats)
    held = collect(range(args.seeds, 2 * args.seeds), args.rays, rng, retreats)
    edge = np.concatenate([calib[(v, "edge")]["wedge"] for v in ("crisp", "scan")])
    other = np.concatenate([calib[(v, "other")]["wedge"] for v in ("crisp", "scan")])
    tau, acc = best_threshold(edge, other, np.arange(10.0, 121.0), above=False)
    report: dict = {"tau_wedge_deg": float(tau), "calibration_balanced_accuracy": acc}
    pct = [1, 5, 50, 95, 99]
    for name, data in (("calibration", calib), ("held_out", held)):
        report[name] = {
            variant: {
                "wedge": accuracy(data, variant, "wedge", tau),
                "dihedral_45": accuracy(data, variant, "dihedral", 45.0),
                "wedge_percentiles_edge": np.percentile(data[(variant, "edge")]["wedge"], pct)
                .round(1)
                .tolist(),
                "wedge_percentiles_other": np.percentile(data[(variant, "other")]["wedge"], pct)
                .round(1)
                .tolist(),
            }
            for variant in ("crisp", "scan")
        }
    report["scan_edge_retreat_mm"] = np.percentile(np.array(retreats) * 1e3, [0, 50, 100]).tolist()
    report["seconds"] = round(time.perf_counter() - t0, 1)
    report["args"] = vars(args)
    print(json.dumps(report, indent=1) if args.json else json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
