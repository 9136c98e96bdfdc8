"""The ε gate of long objects: how many uniform grasps pass it, per family, three ways.

ε (GraspIt!'s, :mod:`affordgrasp.metrics.epsilon`) divides torques by r_max, the largest
distance from the centre of mass to the surface, so the same hold gives a smaller ε on a longer
object (a sword's r_max is 3-4 times a knife's). For each stored table of uniform grasps
(``evaluate_samples`` output, e.g. the cache of ``studies/validate_scan.py``), with
L = min(r_max, r_ref):

* ``before``: ε >= τ_ε (the gate as it was);
* ``scaled``: ε >= τ_ε · L / r_max (design i: the threshold scaled, no new hull);
* ``epsilon_hand``: ε recomputed with torques divided by L instead of r_max, >= τ_ε (design
  ii: one more hull per force-closure grasp, timed here).

Since the torque coordinates of the wrench space are stretched by r_max / L >= 1, ε <=
ε_hand <= ε · r_max / L: design (i) passes every grasp design (ii) passes, and more. Both are
ε itself where r_max <= r_ref.

Run: ``python studies/epsilon_gate.py /tmp/affordgrasp-validation-scan --r-ref 0.25``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from affordgrasp.metrics.contacts import ContactSet
from affordgrasp.metrics.epsilon import epsilon
from affordgrasp.objects import load_object
from affordgrasp.tasks.thresholds import TAU_EPS_DEFAULT


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cache", help="folder of <family>_<seed>~scan_<n>_<materials>.parquet")
    parser.add_argument("--r-ref", type=float, default=0.25, help="m")
    parser.add_argument("--tau", type=float, default=TAU_EPS_DEFAULT)
    parser.add_argument("--seeds", default="0-6")
    parser.add_argument("--out", default="")
    args = parser.parse_args()
    lo, _, hi = args.seeds.partition("-")
    seeds = set(range(int(lo), int(hi or lo) + 1))
    rows = []
    for path in sorted(Path(args.cache).glob("*.parquet")):
        stem = path.stem
        spec_part, n_part, materials = stem.rsplit("_", 2)
        family, _, rest = spec_part.rpartition("_")
        seed = int(rest.split("~")[0])
        if seed not in seeds:
            continue
        spec = f"{family}:{rest}"
        obj = load_object(spec, materials=materials == "True")
        center = np.asarray(obj.mass.center_of_mass, float)
        r_max = float(obj.mass.r_max)
        length = min(r_max, args.r_ref)
        t = pq.read_table(
            path, columns=["epsilon", "contact_points", "contact_normals", "contact_mu"]
        )
        eps = t.column("epsilon").to_numpy()
        fc = np.flatnonzero(eps > 0)
        eps_hand = eps.copy()
        t0 = time.perf_counter()
        if length < r_max:
            pts = t.column("contact_points").to_pylist()
            nrm = t.column("contact_normals").to_pylist()
            mus = t.column("contact_mu").to_pylist()
            for i in fc:
                cs = ContactSet.from_arrays(
                    np.asarray(pts[i], float).reshape(-1, 3),
                    np.asarray(nrm[i], float).reshape(-1, 3),
                    np.asarray(mus[i], float),
                )
                eps_hand[i] = epsilon(cs, center, length, volume=False).epsilon
        seconds = time.perf_counter() - t0
        row = {
            "object": spec,
            "materials": materials == "True",
            "grasps": t.num_rows,
            "r_max_mm": round(1000 * r_max, 1),
            "force_closure": int(fc.size),
            "before": int(np.sum(eps >= args.tau)),
            "scaled": int(np.sum(eps >= args.tau * length / r_max)),
            "epsilon_hand": int(np.sum(eps_hand >= args.tau)),
            "extra_hull_ms": round(1000 * seconds / max(fc.size, 1), 2) if length < r_max else 0,
            "max_ratio": float(np.max(eps_hand[fc] / eps[fc])) if fc.size else 1.0,
        }
        rows.append(row)
        print(json.dumps(row), flush=True)
    if args.out:
        Path(args.out).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
