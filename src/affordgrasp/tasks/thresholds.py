"""Default thresholds of the built-in tasks and the threshold modes of the paper's Table I."""

from __future__ import annotations

import math
from collections.abc import Mapping

TAU_EPS_DEFAULT = 0.3  # paper, Table I
TAU_EPS_EXTRA = 0.5  # paper, Table I, "extra robustness required"
TAU_DELTA_DEFAULT = 0.95  # paper, Table I

# Edge thresholds, calibrated with benchmarks/calibrate_use_edge.py on the built-in
# families (knife, meat_cleaver, axe, dagger, sword; 6 seeds each; 300 direction-mapping
# use points + 300 surface samples + 100 cutting-edge samples per mesh; "edge" = within
# 0.5 mm of the geometric cutting edge, about 3.1k points; "other" = farther than 3 mm on
# the blades, about 17.1k points, plus every point of hammer, screwdriver, bottle and mug,
# 14.2k). Run-to-run differences of ray casting move these numbers in the second digit.
#
# U_g does not separate them: percentiles 5/50/95 are about 0.1 / 800 / 4.5e4 m^-2 on the
# cutting edges and 70 / 2.4e3 / 3.7e4 on blade flats, spines and handles. Two causes,
# both intrinsic to the definition: (1) resolution: U_g scales as 1/h² with the size h of
# the fitted neighbourhood, and the blades' cutting edges are lines of long mesh edges
# (median 3 mm, up to 0.1-0.5 m) with sliver triangles, while spines, bolsters and
# handles have small triangles at their creases; (2) the height function fitted over one
# flank of an acute wedge sees the other flank fold back under the same tangent plane, so
# a sharp edge scores lower than a blunt crease (on one isotropic mesh a 20° edge gives a
# third of a 60° one; tests/metrics/test_use_geometry.py). The threshold that maximises
# the balanced accuracy is kept as the default (3e4 m^-2, balanced accuracy 0.50-0.51:
# about 7% of edge points pass, 94% of the others fail); use the "cut-angle" task
# (use_edge_angle) for cutting with the built-in blades.
TAU_UG_DEFAULT = 3.0e4
# The sharpest-edge angle separates perfectly: cutting-edge points have 14.3-24.5 degrees
# (all of them), other points 89-180 degrees (1st-100th percentile; the lowest non-edge
# value is 65.7 degrees); 45 degrees is the middle of the threshold
# plateau [25, 65] degrees where the balanced accuracy is 1.0.
TAU_EDGE_ANGLE_DEFAULT = math.radians(45.0)

# viable grasp (paper §III-B)
VIABLE_EPS_MIN = 0.15
VIABLE_HOLD_MAX = 250.0
VIABLE_IMPACT_MAX = 100.0

MODES: tuple[str, ...] = ("default", "no-robustness", "extra-robustness")
MODE_EPS: Mapping[str, float] = {
    "default": TAU_EPS_DEFAULT,
    "no-robustness": -math.inf,
    "extra-robustness": TAU_EPS_EXTRA,
}


def standard_modes(thresholds: Mapping[str, float]) -> dict[str, dict[str, float]]:
    """Table I modes restricted to the thresholds a task has (only τ_ε changes)."""
    modes: dict[str, dict[str, float]] = {}
    for mode, tau in MODE_EPS.items():
        modes[mode] = {"tau_eps": tau} if "tau_eps" in thresholds else {}
    return modes
