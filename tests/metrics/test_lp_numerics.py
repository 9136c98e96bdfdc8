"""Nearly degenerate programs met by the optimiser, kept as regression cases.

* A hold-effort program that stalled HiGHS's simplex ("Unknown"), on screwdriver:0: the
  interior-point retry decides it, and the answer matches the independent per-direction
  check with scipy's interior-point solver.
* A hold-effort program on which the compiled simplex ends on a numerically singular final
  basis, on sword:2: the re-solve must hand it to HiGHS instead of raising.
"""

import numpy as np
import scipy.optimize as so

from affordgrasp.metrics.cones import contact_wrenches
from affordgrasp.metrics.contacts import ContactSet
from affordgrasp.metrics.effort import GRAVITY_DIRECTIONS, hold_effort, hold_effort_highs
from affordgrasp.metrics.lp import FAILED, LPStatus, simplex_standard, solve_standard_lp
from affordgrasp.metrics.phi import contact_metrics_batch
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


# A hold-effort program (gravity along -y, 9 of its 32 cone edges: the smallest subset that
# still shows it) on which the tableau simplex ends on a final basis singular to machine
# precision: det(B) = 7e-19, condition number 3e17, an exact zero pivot in the LU of B^T.
# Found by the optimiser (cut, sword:2 at unit density, seed 2, 8 restarts); the re-solve
# raised numpy.linalg.LinAlgError and stopped the search.
SINGULAR_BASIS_A = [
    [-0.13570345868222503, 0.16152139124986148, -0.04810496114407732, 0.3514319533383424,
     -0.43645486036403947, -0.03672469197555255, 0.24592722073678713, -0.06075150545686827,
     0.22156877430846847],
    [1.0055835525353394, 1.0299374811569764, 0.2791352434119463, -0.12033514978273448,
     -0.5476737885178229, -0.2234305023979914, -0.32656996252422243, 0.13119241490938055,
     -0.5333018996144132],
    [0.24573622071662088, -0.05603235740830719, 1.0391195449026451, 1.0109475920637845,
     -0.8182668123754879, -1.0529625385537142, -0.9964295568065048, -1.0672852499941001,
     -0.9091184532936845],
    [-0.004236403800701374, 0.0009659776918829266, 0.016394235373997174,
     0.015949765198900095, -0.012909831985732454, -0.016612636898859248,
     -0.015720713532024564, -0.015315675286698121, -0.013045962231896382],
    [-0.07814450335241235, 0.017818377473901553, -0.38992106094894413, -0.3793497674214516,
     0.3070478899280104, 0.39511553044192615, 0.3739019940934115, 0.46009159808893635,
     0.3919081257946886],
    [0.31743766717261457, 0.3303063039025324, 0.10550215791134214, -0.05069933261051717,
     -0.19862411594671875, -0.0832610508815398, -0.12642269664247788, 0.057426988861598124,
     -0.23307845644793676],
]  # fmt: skip
SINGULAR_BASIS_B = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0]

# The grasp it came from: 4 contacts (the middle two coincide) on sword:2 at unit density.
SWORD_POINTS = [
    [0.10573242812019568, -0.017239638987034504, 0.0],
    [0.1629726342444781, 0.015777045043797285, 0.0],
    [0.1629726342444781, 0.015777045043797285, 0.0],
    [0.21881673778036353, 0.014350124123565849, 0.0],
]  # fmt: skip
SWORD_NORMALS = [
    [0.135703458682225, -0.9892865575332639, 0.053820798820398655],
    [0.04810496114407732, 0.11806079278838008, -0.9918404921757863],
    [0.036724691975552504, 0.5558445888937653, 0.8304746173103799],
    [0.06075150545686822, 0.2554829841938036, 0.9649029481622245],
]  # fmt: skip
SWORD_MU = [0.3, 0.4, 0.4, 0.4]
SWORD_COM = [-0.21226913929744082, 4.866867128171122e-10, 4.980983743776288e-11]
SWORD_R_MAX = 0.6045589822038772
SWORD_USE_POINT = [[-0.23367806117682594, -0.002543181530609705, -0.012880920480615812]]
SWORD_USE_NORMAL = [[-0.7137285054147787, 0.0, -0.7004224586336351]]
SWORD_WRIST_AXIS = [[0.6073638893790904, 0.7944235665044749, -0.0005503277336281649]]


def test_singular_final_basis_goes_to_highs_not_raised():
    A = np.array(SINGULAR_BASIS_A)
    b = np.array(SINGULAR_BASIS_B)
    c = np.ones(A.shape[1])
    status, objective = simplex_standard(A, b, c, np.empty(A.shape[1]))
    assert status == FAILED and np.isnan(objective)  # no certificate from that basis
    got = solve_standard_lp(c, A, b)
    ref = so.linprog(c, A_eq=A, b_eq=b, bounds=(0, None), method="highs")
    assert ref.status == 0
    assert got.status is LPStatus.OPTIMAL
    assert abs(got.objective - ref.fun) < 1e-9 * max(1.0, ref.fun)
    # HiGHS's answer, feasible to its primal tolerance (1e-7)
    assert np.all(got.x >= -1e-7)
    np.testing.assert_allclose(A @ got.x, b, atol=1e-7)


def test_grasp_with_a_singular_final_basis_is_recomputed():
    P = np.array(SWORD_POINTS)
    N = np.array(SWORD_NORMALS)
    mu = np.array(SWORD_MU)
    center = np.array(SWORD_COM)
    *_, hold, impact, force, redo = contact_metrics_batch(
        P,
        N,
        mu,
        np.array([0, len(P)], dtype=np.int64),
        center,
        SWORD_R_MAX,
        np.array(SWORD_USE_POINT),
        np.array(SWORD_USE_NORMAL),
        np.array(SWORD_WRIST_AXIS),
        False,
        False,
    )
    assert redo[0]  # the compiled path gives the grasp back to the reference solvers
    contacts = ContactSet(P, N, mu, np.array(["palm"] * len(P), dtype=object))
    simplex = hold_effort(contacts, center)
    highs = hold_effort(contacts, center, backend="highs")
    np.testing.assert_allclose(simplex, highs, rtol=1e-9)
    assert np.isfinite(simplex[3])  # the -y program of the fixture above is feasible
