"""Cost of the columns beat and cut gained: ``epsilon_hand`` and the striking surface.

    python benchmarks/bench_beat_columns.py [--object sword:4~scan] [--table ROWS.parquet]
        [--use-object hammer:2~scan] [--uses 2000]

``epsilon_hand`` (one more ε hull per force-closure grasp on an object longer than 0.25 m)
is timed on the contacts of evaluated rows (``--table``, e.g. a grasp table cached by
``studies/validate_scan.py``; else 600 grasps of ``--object`` are simulated first), beside ε
itself through its public function on the same grasps. ``use_depth`` and ``use_relief`` (1
and 8 rays per use point) are timed on ``--uses`` use points drawn by area, beside
``use_wedge_angle`` (256 rays). Best of three, wall time per item.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def best_of(f, repeat: int = 3) -> float:
    f()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    import pyarrow.parquet as pq

    from affordgrasp.metrics.contacts import ContactSet
    from affordgrasp.metrics.epsilon import epsilon
    from affordgrasp.metrics.epsilon_hand import epsilon_hand
    from affordgrasp.metrics.striking import use_depth, use_relief
    from affordgrasp.metrics.wedge import use_wedge_angle
    from affordgrasp.objects import load_object
    from affordgrasp.pipeline import evaluate_samples
    from affordgrasp.search.use_points import UsePoints

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--object", default="sword:4~scan")
    parser.add_argument("--table", default="")
    parser.add_argument("--use-object", default="hammer:2~scan")
    parser.add_argument("--uses", type=int, default=2000)
    args = parser.parse_args()

    obj = load_object(args.object)
    table = (
        pq.read_table(args.table)
        if args.table
        else evaluate_samples(obj, 600, seed=0, volume=False).table
    )
    eps = table.column("epsilon").to_numpy()
    pts = table.column("contact_points").to_pylist()
    nrm = table.column("contact_normals").to_pylist()
    mus = table.column("contact_mu").to_pylist()
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in pts])])
    P = np.asarray([x for p in pts for x in p], float).reshape(-1, 3)
    N = np.asarray([x for p in nrm for x in p], float).reshape(-1, 3)
    M = np.asarray([x for m in mus for x in m], float)
    c, r = obj.mass.center_of_mass, obj.mass.r_max
    fc = np.flatnonzero(eps > 0)
    t_hand = best_of(lambda: epsilon_hand(P, N, M, offsets, c, r, eps))
    sets = [
        ContactSet.from_arrays(
            P[offsets[i] : offsets[i + 1]],
            N[offsets[i] : offsets[i + 1]],
            M[offsets[i] : offsets[i + 1]],
        )
        for i in fc
    ]
    t_eps = best_of(lambda: [epsilon(s, c, r, volume=False) for s in sets])
    k = max(len(fc), 1)
    print(
        f"{args.object}: r_max {1000 * r:.0f} mm, {len(eps)} grasps, {len(fc)} force closure; "
        f"epsilon_hand {1e3 * t_hand / k:.2f} ms per force-closure grasp "
        f"({1e3 * t_hand / len(eps):.4f} ms per grasp), epsilon() {1e3 * t_eps / k:.2f} ms"
    )
    use_obj = load_object(args.use_object)
    uses = UsePoints.sample(use_obj, args.uses, seed=0)
    hit = uses.triangle >= 0
    U, UN = uses.point[hit], uses.normal[hit]
    for name, f in (
        ("use_depth", lambda: use_depth(use_obj.mesh_data, U, UN)),
        ("use_relief", lambda: use_relief(use_obj.mesh_data, U, UN)),
        ("use_wedge_angle", lambda: use_wedge_angle(use_obj.mesh_data, U, UN)),
    ):
        print(f"{args.use_object}: {name} {1e6 * best_of(f) / len(U):.1f} us per use point")


if __name__ == "__main__":
    main()
