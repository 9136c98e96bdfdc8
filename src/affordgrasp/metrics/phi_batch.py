"""Φ of a simulated batch: the metric vector of every grasp the policy simulated.

The bridge between the grasp stage's :class:`~affordgrasp.grasp.policy.SimulationBatch` and
:func:`~affordgrasp.metrics.phi.compute_phi_batch`: the evaluation pipeline and the robust
copies (:mod:`affordgrasp.robust`) both score their batches here, so that a copy and a plain
row are scored by the same code.
"""

from __future__ import annotations

import numpy as np

from ..columns import USE_METRICS
from ..grasp.policy import SimulationBatch
from ..objects import GraspObject
from .phi import compute_phi_batch

__all__ = ["phi_of_batch"]


def phi_of_batch(
    obj: GraspObject, batch: SimulationBatch, *, soft: bool = False, volume: bool = False
) -> dict:
    """Φ for every row of a simulation batch.

    A row whose use ray left the object without a hit (from the cavity of a hollow object
    through its opening) has no use point: its use metrics are NaN (undefined), the others
    are computed as usual.

    Parameters
    ----------
    obj : GraspObject
        The object simulated.
    batch : SimulationBatch
        n grasps with their contacts (m, object frame), use points and wrist axes.
    soft : bool
        Soft-finger cones.
    volume : bool
        Also compute ``gws_volume``, the 6-volume of the grasp wrench space (the full 6-D
        hull of every force-closure grasp, most of the metric cost on enveloping grasps).
        False (default): ε alone, the same ε from the exact best-first hull, and
        ``gws_volume`` None (a null column). The paper's Φ has no volume and no task uses it.

    Returns
    -------
    dict of str to (n,) ndarray
        Column name → float64 array (``epsilon_reason``: object array of str;
        ``gws_volume``: None when not computed).
    """
    no_use = batch.use_triangle < 0
    use_point = np.where(no_use[:, None], obj.mass.center_of_mass, batch.use_point)
    use_normal = np.where(no_use[:, None], [1.0, 0.0, 0.0], batch.use_normal)
    use_triangle = np.where(no_use, 0, batch.use_triangle)
    phi: dict = compute_phi_batch(
        obj.mass,
        obj.mesh_data,  # the mesh's arrays, normals and adjacency; no trimesh needed
        batch.contacts,
        use_point,
        use_normal,
        use_triangle,
        batch.wrist_point,
        batch.wrist_axis,
        soft=soft,
        volume=volume,
    )
    if no_use.any():
        for name in USE_METRICS:
            phi[name] = np.where(no_use, np.nan, phi[name])
    if not volume:
        phi["gws_volume"] = None  # not computed: a null column, never a number
    return phi
