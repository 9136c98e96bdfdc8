"""The pipeline of SPEC §2: pregrasp → grasp policy → contacts → metric vector Φ.

``evaluate`` runs it for given inputs; ``evaluate_samples`` draws the inputs from a seed so a
sample's content depends only on (seed, sample index); both return an Arrow table with the
per-sample columns (see ``affordgrasp.schema`` and docs/conventions.md).
"""

from __future__ import annotations

import time

import numpy as np
import pyarrow as pa

from .columns import USE_METRICS
from .grasp.policy import SimulationBatch, simulate
from .grasp.pregrasp import sample_inputs
from .hands import Hand, get_hand
from .metrics.phi import compute_phi_batch
from .objects import GraspObject, resolve_object
from .schema import batch_to_table


def phi_of_batch(obj: GraspObject, batch: SimulationBatch, *, soft: bool = False) -> dict:
    """Φ for every row of a simulation batch: column name → (n,) array.

    A row whose use ray left the object without a hit (from the cavity of a hollow object
    through its opening) has no use point: its use metrics are NaN (undefined), the others
    are computed as usual.
    """
    no_use = batch.use_triangle < 0
    use_point = np.where(no_use[:, None], obj.mass.center_of_mass, batch.use_point)
    use_normal = np.where(no_use[:, None], [1.0, 0.0, 0.0], batch.use_normal)
    use_triangle = np.where(no_use, 0, batch.use_triangle)
    phi = compute_phi_batch(
        obj.mass,
        obj.mesh,
        batch.contacts,
        use_point,
        use_normal,
        use_triangle,
        batch.wrist_point,
        batch.wrist_axis,
        soft=soft,
    )
    if no_use.any():
        for name in USE_METRICS:
            phi[name] = np.where(no_use, np.nan, phi[name])
    return phi


def evaluate(
    obj,
    p0,
    use_dir,
    *,
    hand: Hand | str = "barrett",
    seed: int = -1,
    sample_start: int = 0,
    soft: bool = False,
    metrics: bool = True,
) -> tuple[pa.Table, dict]:
    """Simulate and score given inputs on one object.

    obj : GraspObject or an object spec ("knife", "knife:3", a mesh path)
    p0 : (n, 6) pregrasps; use_dir : (n, 2) use directions
    returns : (table, timings) with timings in seconds: simulate, metrics
    """
    obj = resolve_object(obj)
    hand = get_hand(hand) if isinstance(hand, str) else hand
    t0 = time.perf_counter()
    batch = simulate(obj, p0, use_dir, hand=hand)
    t1 = time.perf_counter()
    phi = phi_of_batch(obj, batch, soft=soft) if metrics else None
    t2 = time.perf_counter()
    table = batch_to_table(
        obj, batch, hand=hand.name, seed=seed, sample_start=sample_start, metrics=phi
    )
    return table, {"simulate": t1 - t0, "metrics": t2 - t1, "table": time.perf_counter() - t2}


def evaluate_samples(
    obj,
    n: int,
    *,
    seed: int = 0,
    start: int = 0,
    hand: Hand | str = "barrett",
    soft: bool = False,
    metrics: bool = True,
) -> tuple[pa.Table, dict]:
    """Draw samples start..start+n-1 of the run ``seed`` uniformly and evaluate them."""
    p0, d = sample_inputs(seed, start, start + n)
    return evaluate(
        obj, p0, d, hand=hand, seed=seed, sample_start=start, soft=soft, metrics=metrics
    )
