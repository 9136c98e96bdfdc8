"""Do the task trials fail where a person fails? Pass rates per labelled part of the tools.

For each tool family: the force-closure grasps (ε > 0) whose every contact lies on the
hilt (handle, guard, pommel) and that pass the hold test, then per grasp one use point drawn
(by area) on each labelled region, and the family's trial (beat: hammer, axe; cut: knife,
meat_cleaver, dagger, sword) run on it. Prints a table per family (rows tried, passed,
medians of the measured quantities) and the CPU time per trial.

    python studies/task_trial_semantics.py [--grasps 8] [--samples 3000] [--materials]
        [--objects hammer axe knife ...] [--set cut_force_n=5 ...] [--json OUT]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np

BEAT = {
    "hammer": {
        "striking face": ("striking_face", None),
        "claw": ("claw", None),
        "handle near the hand": ("handle", "near"),
        "handle, hand to head": ("handle", "far"),
    },
    "axe": {
        "poll (striking face)": ("poll", None),
        "blade edge": ("cutting_edge", None),
        "handle near the hand": ("handle", "near"),
        "handle, hand to head": ("handle", "far"),
    },
}
CUT = {
    "cutting edge": ("cutting_edge", None),
    "spine": ("spine", None),
    "blade flat": ("blade", None),
}
NEAR_M, FAR_M = 0.05, 0.09  # use points this close to / this far from the palm centre


HILT = ("handle", "guard", "pommel")  # where a hand holds a tool


def held_handle_grasps(obj, scene, samples, want, seed):
    """Force-closure grasps with every contact on the hilt (handle, guard, pommel) that pass
    the hold test."""
    import trimesh

    import affordgrasp as ag
    from affordgrasp.physics.trials import validate_grasp

    table = ag.evaluate(obj, samples=samples, seed=seed).table
    parts = np.asarray(obj.face_parts)
    hilt = [obj.part_names.index(p) for p in HILT]
    eps = table.column("epsilon").to_numpy()
    status = np.asarray(table.column("status").to_pylist())
    rows = []
    for i in np.argsort(-eps, kind="stable"):
        if eps[i] <= 0 or len(rows) >= want:
            break
        if status[i] != "grasped":
            continue
        points = np.asarray(table.column("contact_points")[i].as_py()).reshape(-1, 3)
        _, _, tri = trimesh.proximity.closest_point(obj.mesh, points)
        if len(points) == 0 or not np.isin(parts[tri], hilt).all():
            continue
        pose = np.array(table.column("hand_pose")[i].as_py()).reshape(4, 4)
        joints = np.array(table.column("joints")[i].as_py())
        if validate_grasp(scene, pose, joints).hold_ok:
            wrist = np.array(table.column("wrist_point")[i].as_py())
            rows.append((int(i), pose, joints, wrist))
    return rows


def use_point(obj, part, where, wrist, rng):
    """A point drawn by area on the faces of ``part`` (near / far from the wrist)."""
    mesh = obj.mesh
    faces = np.flatnonzero(np.asarray(obj.face_parts) == obj.part_names.index(part))
    if where is not None:
        dist = np.linalg.norm(mesh.triangles_center[faces] - wrist, axis=1)
        faces = faces[dist < NEAR_M] if where == "near" else faces[dist > FAR_M]
    if len(faces) == 0:
        return None
    area = mesh.area_faces[faces]
    f = rng.choice(faces, p=area / area.sum())
    return mesh.triangles_center[f], mesh.face_normals[f]


def _reasons(results, trial, t) -> dict:
    """How many of the failed trials failed each test (a trial can fail several)."""
    if trial == "beat":
        tests = {
            "first contact off U": lambda r: not r.strike_offset_m <= t.beat_max_offset_m,
            "nail advance": lambda r: not r.strike_nail_advance_m >= t.beat_min_advance_m,
            "turned": lambda r: not r.strike_turn_rad < t.max_turn_rad,
            "slipped": lambda r: not r.strike_slip_m < t.max_slip_m,
        }
    else:
        tests = {
            "off the edge": lambda r: not r.stroke_offset_m <= t.cut_max_offset_m,
            "not an edge": lambda r: (
                not (
                    r.stroke_edge_thickness_m <= t.cut_max_thickness_m
                    and r.stroke_edge_angle_rad <= t.cut_max_angle_rad
                )
            ),
            "force": lambda r: not r.stroke_force_n >= t.cut_force_n,
            "turned": lambda r: not r.stroke_turn_rad < t.max_turn_rad,
            "slipped": lambda r: not r.stroke_slip_m < t.max_slip_m,
        }
    failed = [r for r in results if not (r.beat_ok if trial == "beat" else r.cut_ok)]
    return {name: sum(bool(test(r)) for r in failed) for name, test in tests.items()}


def family(spec, trial, cases, args):
    import affordgrasp as ag
    from affordgrasp.metrics.wedge import use_edge_frame
    from affordgrasp.physics.scene import build_scene
    from affordgrasp.physics.task_scene import build_task_scene
    from affordgrasp.physics.task_trials import run_task_trials

    obj = ag.load_object(spec, materials=args.materials)
    scene = build_scene("barrett", obj)
    ts = build_task_scene("barrett", obj, trials=args.trials)
    grasps = held_handle_grasps(obj, scene, args.samples, args.grasps, args.seed)
    out = {}
    for label, (part, where) in cases.items():
        results, cpu = [], []
        for k, (i, pose, joints, wrist) in enumerate(grasps):
            drawn = use_point(obj, part, where, wrist, np.random.default_rng([args.seed, i, k]))
            if drawn is None:
                continue
            point, normal = drawn
            edge = None
            if trial == "cut":
                t = ts.trials
                outward, along = use_edge_frame(
                    obj.mesh, point, normal, radius=t.edge_radius_m, directions=t.edge_directions
                )
                edge = (outward[0], along[0])
            started = time.process_time()
            _grasp, task = run_task_trials(
                scene, ts, pose, joints, [trial], point, normal, wrist, edge
            )
            cpu.append(time.process_time() - started)
            results.append(task.beat if trial == "beat" else task.cut)
        ok = [r.beat_ok if trial == "beat" else r.cut_ok for r in results]
        medians = {
            f: float(np.median([getattr(r, f) for r in results])) if results else float("nan")
            for f in (results[0].__dataclass_fields__ if results else ())
            if not f.endswith("_ok")
        }
        out[label] = {
            "tried": len(results),
            "passed": int(sum(ok)),
            "failed": _reasons(results, trial, ts.trials),
            "median": medians,
            "cpu_ms": 1000 * float(np.mean(cpu)) if cpu else float("nan"),
            "rows": [dataclasses.asdict(r) for r in results],
        }
    return {"grasps": len(grasps), "cases": out}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--objects",
        nargs="*",
        default=["hammer", "axe", "knife", "meat_cleaver", "dagger", "sword"],
    )
    p.add_argument("--grasps", type=int, default=8)
    p.add_argument("--samples", type=int, default=3000)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--materials", action="store_true", help="per-part materials (steel heads)")
    p.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE", help="TrialSettings")
    p.add_argument("--json", default=None)
    args = p.parse_args()
    from affordgrasp.physics.settings import TrialSettings

    kinds = {f.name: type(f.default) for f in dataclasses.fields(TrialSettings)}
    given = dict(a.split("=") for a in args.set)
    args.trials = TrialSettings(**{k: kinds[k](v) for k, v in given.items()})
    report = {}
    for spec in args.objects:
        base = spec.split(":")[0].split("~")[0]
        trial, cases = ("beat", BEAT[base]) if base in BEAT else ("cut", CUT)
        report[spec] = family(spec, trial, cases, args)
        r = report[spec]
        print(f"\n{spec} ({trial}; {r['grasps']} held handle grasps)")
        for label, c in r["cases"].items():
            med = ", ".join(f"{k} {v:.4g}" for k, v in c["median"].items())
            why = ", ".join(f"{k} {v}" for k, v in c["failed"].items())
            print(f"  {label:24s} {c['passed']}/{c['tried']}  cpu {c['cpu_ms']:.0f} ms  [{med}]")
            print(f"  {'':24s} failed: {why}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(report, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
