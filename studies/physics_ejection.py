"""Which force-closure grasps does the squeeze eject, and which protocol constant moves it?

    python studies/physics_ejection.py DATASET OUTCOMES [--variant NAME=JSON ...]
                                          [--every N] [--normals]

DATASET is a directory written by ``affordgrasp generate``; OUTCOMES a physics run of it
(``affordgrasp physics DATASET --out OUTCOMES``), which names the replayed rows. The rows
in force closure by the metrics (ε > 0) are put in the engine (with the back-off) and
squeezed, nothing else (no hold test): a row is ejected when no hand-object contact is
left. Each ``--variant`` is a protocol and setting overrides, e.g.
``'mu0.6={"friction": 0.6}'`` or ``'dgb-mu={"protocol": "dgb", "friction": 0}'``; without
any, our protocol and DGB's. ``--normals`` also measures, at the start, the angle between
each scored contact's mesh normal and the nearest engine contact's normal (within 3 mm;
contacts up to 1 mm apart count), and the ejection rate per bin of each grasp's largest
angle. One process, one core; about 20-30 ms of CPU per row and variant.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np


def _rows(dataset, outcomes, every):
    import pyarrow as pa

    from affordgrasp.dataset import Dataset
    from affordgrasp.physics.run import _plan_rows, read_outcomes

    out = read_outcomes(outcomes)
    eps = np.asarray(out.column("epsilon").to_numpy(zero_copy_only=False), dtype=float)
    keys = set(
        zip(
            np.asarray(out.column("object").to_pylist())[eps > 0].tolist(),
            np.asarray(out.column("sample").to_pylist())[eps > 0].tolist(),
            strict=True,
        )
    )
    dataset = Dataset.open(dataset)
    rows = _plan_rows(dataset, ("grasped",), None, None)
    pairs = zip(rows.column("object").to_pylist(), rows.column("sample").to_pylist(), strict=True)
    sel = [i for i, k in enumerate(pairs) if k in keys][::every]
    return rows.take(pa.array(sel, type=pa.int64())), dataset


def _normal_error(scene, points, normals):
    """Largest angle, degrees, between the scored normals and the nearest engine contact's."""
    from affordgrasp.physics import deps
    from affordgrasp.physics.trials import settled_contacts

    m = scene.model
    margin = m.geom_margin.copy()
    m.geom_margin[:] = 1e-3  # contacts up to 1 mm apart, as the settled contacts
    engine = settled_contacts(scene)
    m.geom_margin[:] = margin
    deps.mujoco().mj_forward(m, scene.data)
    angles = []
    for p, n in zip(points, normals, strict=True):
        if len(engine) == 0:
            break
        d = np.linalg.norm(engine.points - p, axis=1)
        j = int(np.argmin(d))
        if d[j] < 3e-3:
            angles.append(np.degrees(np.arccos(np.clip(engine.normals[j] @ n, -1.0, 1.0))))
    return angles


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset")
    parser.add_argument("outcomes")
    parser.add_argument("--variant", action="append", default=None, metavar="NAME=JSON")
    parser.add_argument("--every", type=int, default=1, help="every N-th force-closure row")
    parser.add_argument("--normals", action="store_true", help="measure the normal error")
    args = parser.parse_args()

    from affordgrasp.hands import hand_to_dict
    from affordgrasp.physics import trials
    from affordgrasp.physics.run import _scene
    from affordgrasp.physics.settings import protocol_settings

    rows, dataset = _rows(args.dataset, args.outcomes, args.every)
    hand_key = json.dumps(hand_to_dict(dataset.hand), sort_keys=True)
    variants = args.variant or ["ours={}", 'dgb={"protocol": "dgb"}']
    names = rows.column("object").to_pylist()
    poses = [np.array(p).reshape(4, 4) for p in rows.column("hand_pose").to_pylist()]
    joints = [np.array(j) for j in rows.column("joints").to_pylist()]
    scored = None
    if args.normals:
        table = dataset.read(columns=["object", "sample", "contact_points", "contact_normals"])
        by_key = {
            (o, s): (np.reshape(p, (-1, 3)), np.reshape(n, (-1, 3)))
            for o, s, p, n in zip(
                *(table.column(c).to_pylist() for c in table.column_names), strict=True
            )
        }
        samples = rows.column("sample").to_pylist()
        scored = [by_key[(o, s)] for o, s in zip(names, samples, strict=True)]
    print(f"{rows.num_rows} force-closure rows")
    for spec in variants:
        label, _, text = spec.partition("=")
        overrides = json.loads(text or "{}")
        settings = protocol_settings(overrides.pop("protocol", "affordgrasp"), **overrides)
        started = time.process_time()
        ejected, worst = [], []
        for i, name in enumerate(names):
            scene = _scene(dataset.hand, hand_key, dataset.object(name), settings)
            trials.set_grasp(scene, poses[i], joints[i])
            if scored is not None:
                angles = _normal_error(scene, *scored[i])
                worst.append(max(angles) if angles else np.nan)
            trials._squeeze(scene)
            ejected.append(trials._hand_contacts(scene) == 0)
        ej, fam = np.array(ejected), np.array([n.split(":")[0] for n in names])
        per = ", ".join(f"{f} {ej[fam == f].mean():.2f}" for f in dict.fromkeys(fam))
        cpu = 1000 * (time.process_time() - started) / max(1, len(ej))
        print(
            f"{label}: ejected {ej.mean():.3f} ({ej.sum()} of {len(ej)}); {per}; {cpu:.0f} ms/row"
        )
        if worst:
            w = np.array(worst)
            for lo, hi in ((0, 3), (3, 6), (6, 9), (9, 180)):
                b = (w > lo) & (w <= hi)
                if b.any():
                    print(
                        f"  largest normal error {lo}-{hi}°: ejected {ej[b].mean():.3f} "
                        f"(n {b.sum()})"
                    )


if __name__ == "__main__":
    main()
