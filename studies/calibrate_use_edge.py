"""Calibrate the edge thresholds of the cut task (τ_Ug and τ_angle) on the built-in families.

The paper's τ_Ug = 10 was in the unknown units of its models, and U_g depends on the
triangle size, so the default threshold is chosen on the procedural families that the
package ships (conventions: Metrics, U_g):

* blade families (knife, meat_cleaver, axe, dagger, sword) over several seeds; their
  *cutting edge* is identified geometrically: convex mesh edges with an interior dihedral
  angle below 45°, on the blade's mid-plane (|z| < 0.5 mm), whose outward bisector faces
  the cutting side (-y for single-edged blades, ±y for double-edged ones);
* use points: the paper's direction mapping (farthest hit of rays from the centre of mass
  in uniformly random directions) plus points sampled directly along the cutting edge
  (0.05-0.4 mm inside an adjacent triangle) and uniformly on the surface;
* labels: "edge" within 0.5 mm of the cutting edge; "other" farther than 3 mm (flat faces,
  spines, tips' flanks, handles, guards); in between is ambiguous and left out. Every
  point of the non-blade families (hammer, screwdriver, bottle, mug) is "other" (handles
  and round parts).

For each threshold candidate the balanced accuracy (mean of the edge pass rate and the
other fail rate) is computed; the printed recommendation is the best one, rounded.

Run: ``python studies/calibrate_use_edge.py [--seeds 6] [--rays 300] [--json]``.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import trimesh

from affordgrasp.metrics.edges import use_edge, use_edge_angle
from affordgrasp.objects.families import make_family

SINGLE_EDGED = ("knife", "meat_cleaver", "axe")
DOUBLE_EDGED = ("dagger", "sword")
NON_BLADES = ("hammer", "screwdriver", "bottle", "mug")
EDGE_DIST_M = 0.5e-3
OTHER_DIST_M = 3e-3


def cutting_edges(mesh: trimesh.Trimesh, double: bool) -> tuple[np.ndarray, np.ndarray]:
    """End points (A, B) of the cutting-edge segments of a blade mesh."""
    angles = mesh.face_adjacency_angles
    sharp = mesh.face_adjacency_convex & (np.pi - angles < np.radians(45.0))
    edges = mesh.face_adjacency_edges
    mid = mesh.vertices[edges].mean(axis=1)
    bis = mesh.face_normals[mesh.face_adjacency].sum(axis=1)
    bis /= np.maximum(np.linalg.norm(bis, axis=1), 1e-12)[:, None]
    side = np.abs(bis[:, 1]) > 0.7 if double else bis[:, 1] < -0.7
    keep = sharp & (np.abs(mid[:, 2]) < 0.5e-3) & side
    return mesh.vertices[edges[keep, 0]], mesh.vertices[edges[keep, 1]]


def distance_to_segments(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    if len(A) == 0:
        return np.full(len(P), np.inf)
    AB = B - A
    t = np.einsum("pij,ij->pi", P[:, None, :] - A[None], AB) / np.einsum("ij,ij->i", AB, AB)
    t = np.clip(t, 0.0, 1.0)
    closest = A[None] + t[..., None] * AB[None]
    return np.linalg.norm(P[:, None, :] - closest, axis=2).min(axis=1)


def direction_mapping(mesh: trimesh.Trimesh, n: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """Farthest hits of rays from the centre of mass (the paper's DM)."""
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    origin = np.repeat(mesh.center_mass[None], n, axis=0)
    loc, ray, tri = mesh.ray.intersects_location(origin, d, multiple_hits=True)
    dist = np.einsum("ij,ij->i", loc - origin[ray], d[ray])
    order = np.lexsort((-dist, ray))
    first = np.unique(ray[order], return_index=True)[1]
    pick = order[first]
    return loc[pick], tri[pick]


def edge_samples(mesh, A, B, n: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """Points just inside a triangle adjacent to the cutting edge."""
    if len(A) == 0:
        return np.zeros((0, 3)), np.zeros(0, dtype=np.int64)
    seg = rng.integers(0, len(A), n)
    t = rng.uniform(0.02, 0.98, n)
    on_edge = A[seg] + t[:, None] * (B[seg] - A[seg])
    closest, _, tri = trimesh.proximity.closest_point(mesh, on_edge)
    # step off the edge into the triangle, towards its centroid
    towards = mesh.triangles_center[tri] - closest
    towards /= np.maximum(np.linalg.norm(towards, axis=1), 1e-12)[:, None]
    step = rng.uniform(0.05e-3, 0.4e-3, n)
    return closest + step[:, None] * towards, tri


def collect(seeds: int, rays: int, rng) -> dict[str, dict[str, np.ndarray]]:
    groups: dict[str, list] = {"edge": [], "blade_other": [], "non_blade": []}
    for name in SINGLE_EDGED + DOUBLE_EDGED + NON_BLADES:
        for seed in range(seeds):
            mesh = make_family(name, seed)
            blade = name not in NON_BLADES
            A, B = cutting_edges(mesh, name in DOUBLE_EDGED) if blade else (np.zeros((0, 3)),) * 2
            P1, T1 = direction_mapping(mesh, rays, rng)
            P2, T2 = trimesh.sample.sample_surface(mesh, rays, seed=int(rng.integers(1 << 31)))
            P3, T3 = edge_samples(mesh, A, B, rays // 3, rng) if blade else (None, None)
            parts = [(P1, T1), (P2, T2)] + ([(P3, T3)] if P3 is not None else [])
            P = np.concatenate([p for p, _ in parts])
            T = np.concatenate([t for _, t in parts]).astype(np.int64)
            ug = use_edge(mesh, T, P)
            ang = use_edge_angle(mesh, P)
            if blade:
                dist = distance_to_segments(P, A, B)
                for label, mask in (
                    ("edge", dist <= EDGE_DIST_M),
                    ("blade_other", dist >= OTHER_DIST_M),
                ):
                    groups[label].append((ug[mask], ang[mask], np.full(mask.sum(), name)))
            else:
                groups["non_blade"].append((ug, ang, np.full(len(P), name)))
    return {
        label: {
            "use_edge": np.concatenate([g[0] for g in items]),
            "use_edge_angle": np.concatenate([g[1] for g in items]),
            "family": np.concatenate([g[2] for g in items]),
        }
        for label, items in groups.items()
    }


def best_threshold(pos: np.ndarray, neg: np.ndarray, candidates: np.ndarray, above: bool):
    """Threshold maximising the balanced accuracy; ``above``: positives are >= τ.

    Ties (a plateau of equally good candidates) resolve to the plateau's middle candidate,
    the choice with the largest margin to both classes.
    """
    scores = []
    for tau in candidates:
        tpr = np.mean(pos >= tau) if above else np.mean(pos <= tau)
        tnr = np.mean(neg < tau) if above else np.mean(neg > tau)
        scores.append(0.5 * (tpr + tnr))
    scores = np.asarray(scores)
    best = np.flatnonzero(scores >= scores.max() - 1e-12)
    # the longest run of consecutive best candidates
    runs = np.split(best, np.flatnonzero(np.diff(best) > 1) + 1)
    run = max(runs, key=len)
    return candidates[run[len(run) // 2]], float(scores.max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--rays", type=int, default=300)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    data = collect(args.seeds, args.rays, rng)
    edge = data["edge"]
    other = {
        k: np.concatenate([data["blade_other"][k], data["non_blade"][k]])
        for k in ("use_edge", "use_edge_angle")
    }
    pct = [1, 5, 25, 50, 75, 95, 99]
    report: dict = {
        "counts": {k: int(len(v["use_edge"])) for k, v in data.items()},
        "percentiles": pct,
        "seconds": None,
    }
    for key in ("use_edge", "use_edge_angle"):
        report[key] = {label: np.percentile(v[key], pct).tolist() for label, v in data.items()}
    ug_tau, ug_acc = best_threshold(
        edge["use_edge"], other["use_edge"], np.logspace(0, 7, 141), above=True
    )
    ang_tau, ang_acc = best_threshold(
        edge["use_edge_angle"], other["use_edge_angle"], np.radians(np.arange(10, 121)), above=False
    )
    ug_round = float(f"{ug_tau:.0e}")
    ang_round = float(np.radians(5 * np.floor(np.degrees(ang_tau) / 5)))

    def rates(tau_ug, tau_ang):
        return {
            "use_edge": {
                "edge_pass": float(np.mean(edge["use_edge"] >= tau_ug)),
                "blade_other_fail": float(np.mean(data["blade_other"]["use_edge"] < tau_ug)),
                "non_blade_fail": float(np.mean(data["non_blade"]["use_edge"] < tau_ug)),
            },
            "use_edge_angle": {
                "edge_pass": float(np.mean(edge["use_edge_angle"] <= tau_ang)),
                "blade_other_fail": float(np.mean(data["blade_other"]["use_edge_angle"] > tau_ang)),
                "non_blade_fail": float(np.mean(data["non_blade"]["use_edge_angle"] > tau_ang)),
            },
        }

    report["best"] = {
        "tau_ug": float(ug_tau),
        "tau_ug_balanced_accuracy": float(ug_acc),
        "tau_angle_deg": float(np.degrees(ang_tau)),
        "tau_angle_balanced_accuracy": float(ang_acc),
    }
    report["recommended"] = {
        "tau_ug": ug_round,
        "tau_angle_deg": float(np.degrees(ang_round)),
        "rates": rates(ug_round, ang_round),
    }
    report["seconds"] = round(time.perf_counter() - t0, 1)
    if args.json:
        print(json.dumps(report, indent=2))
        return
    print(f"use points: {report['counts']}  ({report['seconds']} s)")
    for key, unit in (("use_edge", "m^-2"), ("use_edge_angle", "deg")):
        print(f"\n{key} percentiles {pct} ({unit})")
        for label, values in report[key].items():
            vals = np.degrees(values) if key == "use_edge_angle" else np.asarray(values)
            print(f"  {label:12s} " + "  ".join(f"{v:10.3g}" for v in vals))
    print("\nbest:", report["best"])
    print("recommended:", json.dumps(report["recommended"], indent=1))


if __name__ == "__main__":
    main()
