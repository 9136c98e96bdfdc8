"""Momentum discharge efficiency δ (conventions: Metrics).

The hand swings positively about the wrist axis (unit ``a`` through the wrist point
``w``). At impact the environment pushes on the use point ``U`` along the inward normal
``n_in``; the moment of that force about the wrist point is ``M = (U - w) x n_in``. The
torque that stops the swing is along ``-a``, so::

    δ = max(0, M . (-a) / |M|),   δ = 0 when |M| ≈ 0 (the force line meets the wrist point).

δ = 1 when the outward normal at U points along the swing velocity ``a x (U - w)`` and
the lever ``U - w`` is perpendicular to ``a``; δ = 0 when the force line passes through the
axis or pushes the swing forward. Dimensionless, invariant to rigid motions and scaling.
Validated against these two closed cases in ``tests/metrics/test_discharge.py``.
"""

from __future__ import annotations

import numpy as np

from ..tolerances import ZERO_MOMENT
from .validation import points_n3, units_n3

MOMENT_TOL = ZERO_MOMENT  # |M| below this fraction of |U - w| counts as a zero moment


def discharge(use_point, use_normal, wrist_point, wrist_axis) -> float | np.ndarray:
    """Momentum discharge efficiency δ ∈ [0, 1] (conventions: Metrics).

    Parameters
    ----------
    use_point : (3,) or (n, 3) float
        The use point U, m.
    use_normal : (3,) or (n, 3) float
        Outward unit normal at U.
    wrist_point : (3,) or (n, 3) float
        A point of the wrist axis (the palm centre), m.
    wrist_axis : (3,) or (n, 3) float
        Direction +a of the wrist axis.

    Returns
    -------
    float or (n,) float64 ndarray
        A float for single inputs.
    """
    single = np.ndim(use_point) == 1
    U = points_n3(use_point, "use_point")
    n_in = -units_n3(use_normal, "use_normal")
    w = points_n3(wrist_point, "wrist_point")
    a = units_n3(wrist_axis, "wrist_axis")
    U, n_in, w, a = np.broadcast_arrays(U, n_in, w, a)
    lever = U - w
    M = np.cross(lever, n_in)
    norm = np.linalg.norm(M, axis=1)
    scale = np.maximum(np.linalg.norm(lever, axis=1), np.finfo(float).tiny)
    ok = norm > MOMENT_TOL * scale
    cosine = np.zeros(norm.shape)
    cosine[ok] = -np.einsum("ij,ij->i", M[ok], a[ok]) / norm[ok]
    delta = np.clip(cosine, 0.0, 1.0) + 0.0  # + 0.0 turns -0.0 into 0.0
    return float(delta[0]) if single else delta
