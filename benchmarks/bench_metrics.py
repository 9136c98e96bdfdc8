"""Throughput of the metric vector Φ (conventions: Metrics) on random, realistic contact sets.

Contact sets of 3-10 contacts are sampled on the surface of a built-in family object (a
knife by default) with the object's outward normals and plastic-wood friction (μ = 0.4),
a use point from the paper's direction mapping and a random wrist axis. Prints the time
per grasp of each metric through its public function, of the compiled batch kernels, and
the end-to-end Φ throughput (grasps/s on one core).

Run: ``python benchmarks/bench_metrics.py [--object knife] [--grasps 2000] [--json]``.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import trimesh

from affordgrasp.metrics import (
    compute_phi_batch,
    discharge,
    epsilon,
    hold_effort,
    impact_effort,
    rotational_inertia,
    use_edge,
    use_edge_angle,
    use_force,
)
from affordgrasp.metrics.cones import wrench_matrix_kernel
from affordgrasp.metrics.contacts import ContactSet
from affordgrasp.metrics.epsilon import epsilon_kernel
from affordgrasp.metrics.phi import _stack_contacts, contact_metrics_batch
from affordgrasp.objects.mass import mass_properties


def load_object(name: str) -> trimesh.Trimesh:
    try:
        from affordgrasp.objects.families import make_family

        return make_family(name, 0)
    except Exception:  # noqa: BLE001 - fall back to a plain box when families are missing
        return trimesh.creation.box(extents=(0.2, 0.04, 0.03))


def sample_grasps(mesh: trimesh.Trimesh, n: int, seed: int = 0):
    """n grasps: 3-10 contacts clustered within a hand-sized ball, DM use points."""
    rng = np.random.default_rng(seed)
    pts, faces = trimesh.sample.sample_surface(mesh, 200 * n, seed=seed)
    normals = mesh.face_normals[faces]
    contacts = []
    for _ in range(n):
        k = int(rng.integers(3, 11))
        centre = pts[rng.integers(len(pts))]
        near = np.flatnonzero(np.linalg.norm(pts - centre, axis=1) < 0.08)
        pick = rng.choice(near, size=min(k, len(near)), replace=False)
        contacts.append(ContactSet.from_arrays(pts[pick], normals[pick], 0.4))
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    com = mesh.center_mass
    origin = np.repeat(com[None], n, axis=0)
    loc, ray, tri = mesh.ray.intersects_location(origin, d, multiple_hits=True)
    dist = np.einsum("ij,ij->i", loc - origin[ray], d[ray])
    order = np.lexsort((-dist, ray))
    first = order[np.unique(ray[order], return_index=True)[1]]
    use_point = np.repeat(com[None], n, axis=0)
    use_tri = np.zeros(n, dtype=np.int64)
    use_point[ray[first]] = loc[first]
    use_tri[ray[first]] = tri[first]
    use_normal = mesh.face_normals[use_tri]
    wrist_point = com + rng.normal(size=(n, 3)) * 0.1
    wrist_axis = rng.normal(size=(n, 3))
    return contacts, use_point, use_normal, use_tri, wrist_point, wrist_axis


def per_grasp_us(fn, n: int) -> float:
    t0 = time.perf_counter()
    for i in range(n):
        fn(i)
    return (time.perf_counter() - t0) / n * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--object", default="knife")
    parser.add_argument("--grasps", type=int, default=2000)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    mesh = load_object(args.object)
    mass = mass_properties(mesh)
    c, r = mass.center_of_mass, mass.r_max
    n = args.grasps
    contacts, U, nU, T, w, a = sample_grasps(mesh, n)
    # warm up: compile / load the numba caches and build the per-mesh caches
    compute_phi_batch(mass, mesh, contacts[:20], U[:20], nU[:20], T[:20], w[:20], a[:20])

    m = min(n, 500)
    report: dict = {"object": args.object, "grasps": n, "contacts_mean": None}
    report["contacts_mean"] = float(np.mean([len(cs) for cs in contacts]))
    eps = [epsilon(cs, c, r) for cs in contacts[:m]]
    closure = np.array([e.epsilon > 0 for e in eps])
    report["force_closure_fraction"] = float(closure.mean())

    # per-metric public functions (one call per grasp: includes input validation)
    t = {}
    t["epsilon"] = per_grasp_us(lambda i: epsilon(contacts[i], c, r), m)
    idx_fc = np.flatnonzero(closure)
    idx_nfc = np.flatnonzero(~closure)
    if len(idx_fc):
        t["epsilon (force closure only)"] = per_grasp_us(
            lambda i: epsilon(contacts[idx_fc[i]], c, r), len(idx_fc)
        )
    if len(idx_nfc):
        t["epsilon (not force closure)"] = per_grasp_us(
            lambda i: epsilon(contacts[idx_nfc[i]], c, r), len(idx_nfc)
        )
    t["hold_effort (6 LPs)"] = per_grasp_us(lambda i: hold_effort(contacts[i], c), m)
    t["hold_effort, HiGHS backend"] = per_grasp_us(
        lambda i: hold_effort(contacts[i], c, backend="highs"), min(m, 200)
    )
    t["impact_effort"] = per_grasp_us(lambda i: impact_effort(contacts[i], c, U[i], nU[i], a[i]), m)
    t["use_force"] = per_grasp_us(lambda i: use_force(contacts[i], c, U[i], nU[i]), m)
    t["discharge"] = per_grasp_us(lambda i: discharge(U[i], nU[i], w[i], a[i]), m)
    t["inertia"] = per_grasp_us(lambda i: rotational_inertia(mass, w[i], a[i]), m)
    t["use_edge (U_g)"] = per_grasp_us(lambda i: use_edge(mesh, T[i], U[i]), m)
    t["use_edge_angle"] = per_grasp_us(lambda i: use_edge_angle(mesh, U[i]), m)

    # compiled kernels alone
    points, normals, mu, offsets = _stack_contacts(contacts)
    inv_r = 1.0 / r

    def eps_kernel(i):
        s, e = offsets[i], offsets[i + 1]
        epsilon_kernel(wrench_matrix_kernel(points[s:e], normals[s:e], mu[s:e], c, inv_r, False))

    t["kernel: epsilon"] = per_grasp_us(eps_kernel, m)
    Un = nU / np.linalg.norm(nU, axis=1)[:, None]
    an = a / np.linalg.norm(a, axis=1)[:, None]
    t0 = time.perf_counter()
    contact_metrics_batch(points, normals, mu, offsets, c, r, U, Un, an, False, True)
    t["kernel: all contact metrics (batch)"] = (time.perf_counter() - t0) / n * 1e6
    t0 = time.perf_counter()
    use_edge(mesh, T, U)
    t["batch: use_edge"] = (time.perf_counter() - t0) / n * 1e6
    t0 = time.perf_counter()
    use_edge_angle(mesh, U)
    t["batch: use_edge_angle"] = (time.perf_counter() - t0) / n * 1e6

    # end to end
    t0 = time.perf_counter()
    compute_phi_batch(mass, mesh, contacts, U, nU, T, w, a)
    dt = time.perf_counter() - t0
    report["us_per_grasp"] = {k: round(v, 1) for k, v in t.items()}
    report["phi_us_per_grasp"] = round(dt / n * 1e6, 1)
    report["phi_grasps_per_s"] = round(n / dt, 1)
    if args.json:
        print(json.dumps(report, indent=2))
        return
    print(
        f"object {args.object}, {n} grasps, {report['contacts_mean']:.1f} contacts on average, "
        f"{100 * report['force_closure_fraction']:.0f}% force closure"
    )
    for k, v in report["us_per_grasp"].items():
        print(f"  {k:40s} {v:10.1f} us/grasp")
    print(
        f"Φ (compute_phi_batch): {report['phi_us_per_grasp']:.1f} us/grasp = "
        f"{report['phi_grasps_per_s']:.0f} grasps/s on one core"
    )


if __name__ == "__main__":
    main()
