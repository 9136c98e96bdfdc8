"""ε at a hand's torque length (``epsilon_hand``): the robustness gate of long objects.

GraspIt!'s ε (:mod:`.epsilon`, conventions: Metrics) divides every torque by r_max, the
largest distance from the centre of mass to the surface. The same hold then gives a smaller
ε on a longer object: a torque of 1 N·m is 1 / r_max in the wrench space, so a sword (r_max
0.53-0.73 m) needs three times the torque of a knife (0.17-0.24 m) for the same ε, and the
tasks' τ_ε, calibrated on the built-in families (most of them within 0.25 m), is out of
reach on it (2 of 15,000 uniform grasps of scan-like swords; docs/validation.md §7).

``epsilon_hand`` is the same ε with torques divided by L = min(r_max, r_ref) instead, r_ref =
:data:`EPSILON_HAND_LENGTH_M` (0.25 m: the largest r_max of the one-hand tools the thresholds
were calibrated on, knives, daggers, spatulas and hammers, and about the span of the Barrett hand,
whose fingers reach 0.18 m from the palm's spread axes). A gate on it asks the same torque in
N·m of every object longer than r_ref, and is ε itself (the same bits) on every object within
r_ref. Stretching the torque coordinates by r_max / L >= 1 keeps the origin inside the hull
exactly when it was, so ``epsilon_hand`` is 0 exactly where ε is 0, and ε <= ``epsilon_hand``
<= ε · r_max / L (tests/metrics/test_epsilon_hand.py).

Cost: one more ε hull (facets nearest the origin only) per force-closure grasp, on objects
longer than r_ref only: 0.7-2 ms per such grasp on scan-like axes and swords
(``studies/epsilon_gate.py``), i.e. a few per cent of a simulation's cost, since 1-4 % of
uniform grasps are force closure there.
"""

from __future__ import annotations

import numpy as np

from .cones import wrench_matrix_kernel
from .epsilon import (
    CLOSURE,
    HULL_FALLBACK,
    LP_FALLBACK,
    epsilon_from_wrenches_qhull,
    epsilon_volume_kernel,
)
from .validation import positive_length

EPSILON_HAND_LENGTH_M = 0.25  # r_ref, m (see the module docstring)


def epsilon_torque_length(r_max: float, length: float = EPSILON_HAND_LENGTH_M) -> float:
    """The torque length of ``epsilon_hand``: min(r_max, length), m.

    Parameters
    ----------
    r_max : float
        The object's largest centre-of-mass-to-surface distance, m.
    length : float
        r_ref, m (default :data:`EPSILON_HAND_LENGTH_M`).

    Returns
    -------
    float
        m.
    """
    return min(positive_length(r_max, "r_max"), positive_length(length, "length"))


def epsilon_hand(
    points,
    normals,
    mu,
    offsets,
    center,
    r_max: float,
    epsilon,
    *,
    soft: bool = False,
    length: float = EPSILON_HAND_LENGTH_M,
) -> np.ndarray:
    """ε of many grasps with torques divided by min(r_max, ``length``) (``epsilon_hand``).

    Parameters
    ----------
    points, normals : (K, 3) float
        All contacts (m; the object's outward unit normals), grasp i owning rows
        ``offsets[i]:offsets[i + 1]``.
    mu : (K,) float
        Friction coefficients.
    offsets : (n + 1,) int
        Row ranges of the grasps.
    center : (3,) float
        The torques' reference point (the centre of mass), m.
    r_max : float
        ε's torque length (largest centre-of-mass-to-vertex distance), m.
    epsilon : (n,) float
        The grasps' ε (torques / r_max): returned as it is where r_max <= ``length``, and
        only its force-closure grasps (ε > 0) get the second hull otherwise.
    soft : bool
        Soft-finger cones, as for ε.
    length : float
        r_ref, m.

    Returns
    -------
    (n,) float64 ndarray
        >= ε, 0 where ε is 0, NaN where ε is NaN.
    """
    eps = np.array(epsilon, dtype=np.float64).reshape(-1)
    offsets = np.asarray(offsets, dtype=np.int64).reshape(-1)
    if offsets.shape[0] != eps.shape[0] + 1:
        raise ValueError(
            f"offsets has {offsets.shape[0]} entries, expected one more than the grasps "
            f"({eps.shape[0]})"
        )
    r_max = positive_length(r_max, "r_max")
    torque_length = epsilon_torque_length(r_max, length)
    if torque_length >= r_max:
        return eps
    P = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    N = np.ascontiguousarray(np.asarray(normals, dtype=np.float64).reshape(-1, 3))
    M = np.ascontiguousarray(np.asarray(mu, dtype=np.float64).reshape(-1))
    c = np.array(center, dtype=np.float64).reshape(3)
    # one hull per force-closure grasp, each compiled; the loop is over the 1-4 % of grasps
    # that are force closure, so Python's share is small beside the hulls
    for i in np.flatnonzero(eps > 0):
        s, e = offsets[i], offsets[i + 1]
        W = wrench_matrix_kernel(P[s:e], N[s:e], M[s:e], c, 1.0 / torque_length, bool(soft))
        code, value, _ = epsilon_volume_kernel(W, False)
        if code in (HULL_FALLBACK, LP_FALLBACK):
            code, value, _ = epsilon_from_wrenches_qhull(W)
        # the stretch keeps force closure; a solver that disagrees keeps ε (a lower bound)
        eps[i] = max(float(value), eps[i]) if code == CLOSURE else eps[i]
    return eps
