"""A nearly degenerate hold-effort program that stalled HiGHS's simplex ("Unknown").

Found by the optimiser on screwdriver:0; the interior-point retry decides it, and the
answer matches the independent per-direction check with scipy's interior-point solver.
"""

import numpy as np
import scipy.optimize as so

from affordgrasp.metrics.cones import contact_wrenches
from affordgrasp.metrics.effort import GRAVITY_DIRECTIONS, hold_effort_highs
from affordgrasp.pipeline import evaluate_inputs

P0 = [[-0.12506416086968986, 0.9139600077331622, -0.00145085628569364, -0.29968312816988174,
       0.6926266665706913, 0.263220983843203]]  # fmt: skip
USE = [[-0.6556178262023638, 0.8415510768293228]]


def test_stalled_simplex_is_decided_not_raised():
    from affordgrasp.grasp.policy import simulate
    from affordgrasp.objects import load_object

    obj = load_object("screwdriver")
    contacts = simulate(obj, np.array(P0)).contacts[0]
    W = contact_wrenches(contacts.points, contacts.normals, contacts.mu, obj.mass.center_of_mass)
    got = hold_effort_highs(W)
    for value, g in zip(got, GRAVITY_DIRECTIONS, strict=True):
        ref = so.linprog(np.ones(W.shape[1]), A_eq=W, b_eq=-np.r_[g, 0, 0, 0], method="highs-ipm")
        if ref.status == 2:
            assert value == np.inf
        else:
            assert ref.status == 0
            assert value == np.float64(ref.fun) or abs(value - ref.fun) < 1e-6 * max(1, ref.fun)
    table = evaluate_inputs("screwdriver", P0, USE).table
    assert table.num_rows == 1
