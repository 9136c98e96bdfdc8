"""Cost of ε and the GWS volume on force-closure grasps: full hull, ε only, qhull.

    python benchmarks/bench_gws.py [--samples 400] [--objects sphere mug hammer] [--qhull 30]

Grasps are simulated (no metrics) on each object; the wrench matrices of their contacts are
then scored three ways, CPU time per force-closure grasp: the compiled full hull (ε and the
volume, what the pipeline computes), the compiled best-first hull (ε only,
``epsilon(..., volume=False)``) and scipy's qhull (the reference, on the first ``--qhull``
grasps). ``sphere`` is a trimesh icosphere (subdivisions 4, radius 40 mm). The last row is a
grasp with the palm flat on a wine glass's round foot (36 contacts), the case that made the
optimiser slow. ε must agree to 1e-9 between the three.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

FOOT = ("wine_glass:2", [0.7378, -1.0, -0.9868, -0.0953, 0.1417, 0.4637], [-0.1157, 0.0028])


def wrench_sets(table, obj):
    """Normalised wrench matrices of every grasp with contacts."""
    from affordgrasp.metrics.cones import wrench_matrix_kernel

    center = np.asarray(obj.mass.center_of_mass, dtype=float)
    inv_r = 1.0 / float(obj.mass.r_max)
    out = []
    columns = zip(
        table.column("contact_points").to_pylist(),
        table.column("contact_normals").to_pylist(),
        table.column("contact_mu").to_pylist(),
        strict=True,
    )
    for pts, nrm, mu in columns:
        if not pts:
            continue
        P = np.ascontiguousarray(np.asarray(pts, dtype=float).reshape(-1, 3))
        N = np.ascontiguousarray(np.asarray(nrm, dtype=float).reshape(-1, 3))
        M = np.ascontiguousarray(np.asarray(mu, dtype=float))
        out.append(wrench_matrix_kernel(P, N, M, center, inv_r, False))
    return out


def cpu_ms(fn, W, repeat=1):
    t0 = time.process_time()
    for _ in range(repeat):
        res = fn(W)
    return (time.process_time() - t0) / repeat * 1e3, res


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=400)
    parser.add_argument("--objects", nargs="+", default=["sphere", "mug", "hammer"])
    parser.add_argument("--qhull", type=int, default=30, help="grasps scored with qhull too")
    args = parser.parse_args()

    import tempfile
    from pathlib import Path

    import trimesh

    from affordgrasp.metrics.epsilon import (
        CLOSURE,
        epsilon_from_wrenches_qhull,
        epsilon_volume_kernel,
    )
    from affordgrasp.objects import load_object
    from affordgrasp.pipeline import evaluate_inputs, evaluate_samples

    def full(W):
        return epsilon_volume_kernel(W, True)

    def eps_only(W):
        return epsilon_volume_kernel(W, False)

    sphere = Path(tempfile.mkdtemp(prefix="affordgrasp-bench-")) / "sphere.stl"
    trimesh.creation.icosphere(subdivisions=4, radius=0.04).export(sphere)
    cases = []
    for spec in args.objects:
        obj = load_object(str(sphere) if spec == "sphere" else spec)
        table = evaluate_samples(obj, args.samples, seed=0, metrics=False).table
        cases.append((spec, wrench_sets(table, obj)))
    obj = load_object(FOOT[0])
    table = evaluate_inputs(obj, [FOOT[1]], [FOOT[2]], metrics=False).table
    cases.append(("wine-glass foot", wrench_sets(table, obj)))
    full(cases[0][1][0])  # load the kernels
    eps_only(cases[0][1][0])

    print("CPU ms per force-closure grasp (ε + volume: full hull; ε only: best-first hull)")
    print(
        f"{'object':<16}{'closure':>8}{'contacts':>9}{'ε+volume':>10}{'ε only':>9}"
        f"{'ratio':>7}{'qhull':>9}{'max |Δε|':>10}"
    )
    for name, sets in cases:
        t_full = t_eps = t_q = 0.0
        n_fc = n_q = 0
        contacts = []
        worst = 0.0
        repeat = 3 if len(sets) == 1 else 1
        for i, W in enumerate(sets):
            ms, (code, eps, _) = cpu_ms(full, W, repeat)
            if code != CLOSURE:
                continue
            n_fc += 1
            contacts.append(W.shape[1] // 8)
            t_full += ms
            ms, (_, eps_fast, _) = cpu_ms(eps_only, W, repeat)
            t_eps += ms
            worst = max(worst, abs(eps_fast - eps))
            if i < args.qhull:
                ms, (_, eps_ref, _) = cpu_ms(epsilon_from_wrenches_qhull, W)
                t_q += ms
                n_q += 1
                worst = max(worst, abs(eps_ref - eps))
        if n_fc == 0:
            print(f"{name:<16}{'0':>8}")
            continue
        q = f"{t_q / n_q:>9.2f}" if n_q else f"{'-':>9}"
        print(
            f"{name:<16}{n_fc / len(sets):>8.0%}{np.mean(contacts):>9.1f}{t_full / n_fc:>10.2f}"
            f"{t_eps / n_fc:>9.2f}{t_full / max(t_eps, 1e-12):>7.1f}{q}{worst:>10.1e}"
        )


if __name__ == "__main__":
    main()
