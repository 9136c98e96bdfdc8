"""The contact search against a brute-force reference, and the work it does on fixed cases.

The reference evaluates every sample's distance to every link on a dense grid of the motion
parameter with plain numpy (its own forward kinematics, scipy rotations): the search must
stop where a sample has reached the hit level while no sample ever came closer than half of
it before (the documented stopping gap), for the approach (a translation), a Barrett
finger (two coupled revolute joints) and each jaw of the parallel gripper (a slide, one of
them along -axis).
"""

from types import SimpleNamespace

import numpy as np
import pytest
from grasp_support import shape_sdf
from scipy.spatial.transform import Rotation

from affordgrasp.grasp import kernels
from affordgrasp.grasp.policy import HIT_EPS, close_fingers, hand_arrays
from affordgrasp.hands import get_hand
from affordgrasp.hands.kinematics import REVOLUTE
from affordgrasp.objects.surface import group_into_cells
from affordgrasp.tolerances import JOINT_AT_LIMIT

HIT = 1e-3  # m: coarse enough for a 2000-step reference grid to resolve the stopping gap
# The work of the fixed searches of test_the_search_does_no_more_work_than_measured, as
# measured. The previous release (2671c7c) did the same approach and, for the closing,
# 3338 pops, 3488 queries and 98 refinement queries: the speed bound on the joint origins'
# motion (see kernels._chain_touch) takes longer steps, so a little more bisection on the
# wider last step.
APPROACH_POPS = 1585
APPROACH_QUERIES = 1585
CLOSING_POPS = 2544
CLOSING_QUERIES = 2694
CLOSING_REFINE = 104


def sphere_cloud(center, radius, n, rng):
    """A SampleCloud of n points on a sphere (object frame = hand frame here)."""
    v = rng.normal(size=(n, 3))
    points = center + radius * v / np.linalg.norm(v, axis=1, keepdims=True)
    order, (fs, fc, fr), (cs, cc, cr) = group_into_cells(points)
    p = np.ascontiguousarray(points[order])
    return kernels.SampleCloud(p, fs, fc, fr, cs, cc, cr), p


def finger_chain(hand_name, finger, dofs):
    """A finger's closing chain with every joint active, as the policy builds it."""
    hand = get_hand(hand_name)
    arrays = hand_arrays(hand)
    f = arrays.fingers[finger]
    chain_index, shapes = f.shapes[0]
    s_max = min((f.upper[j] - dofs[f.dofs[j]]) / f.speeds[j] for j in range(len(f.dofs)))
    chain = kernels.Chain(
        arrays.link_poses(dofs)[f.parent],
        f.origins,
        f.kinds,
        f.axes,
        f.ratios * dofs[f.dofs],
        f.ratios * f.speeds,
        chain_index,
        shapes,
    )
    return chain, s_max


def approach_chain(hand_name, dofs):
    """The approach as a chain: one slide along +z carrying every shape."""
    shapes = hand_arrays(get_hand(hand_name)).posed_shapes(dofs)
    k = len(shapes.kinds)
    return kernels.Chain(
        np.eye(4),
        np.eye(4)[None],
        np.array([kernels.PRISMATIC]),
        np.array([[0.0, 0.0, 1.0]]),
        np.zeros(1),
        np.ones(1),
        np.zeros(k, dtype=np.int64),
        shapes,
    )


def shape_poses_at(chain, s):
    """The chain's shape poses at motion parameter s (numpy, independent of the kernels)."""
    t = chain.base.copy()
    links = []
    for j in range(len(chain.kinds)):
        q = chain.q0[j] + chain.speeds[j] * s
        motion = np.eye(4)
        if chain.kinds[j] == REVOLUTE:
            motion[:3, :3] = Rotation.from_rotvec(chain.axes[j] * q).as_matrix()
        else:
            motion[:3, 3] = chain.axes[j] * q
        t = t @ chain.origins[j] @ motion
        links.append(t)
    return [
        links[j] @ local for j, local in zip(chain.shape_joint, chain.shapes.local, strict=True)
    ]


def distances(points, chain, s):
    """(shapes, points) signed distances at s."""
    sh = chain.shapes
    return np.array(
        [
            shape_sdf(points, pose, kind, half, r)
            for pose, kind, half, r in zip(
                shape_poses_at(chain, s), sh.kinds, sh.halves, sh.radii, strict=True
            )
        ]
    )


def check_against_reference(cloud, points, chain, s_max, s, point, shape):
    grid = np.linspace(0.0, s_max, 2001)
    nearest = np.array([distances(points, chain, g).min() for g in grid])
    if not np.isfinite(s):
        assert point == -1 and shape == -1
        # nothing reached the hit level, up to the grid's resolution
        assert nearest.min() > 0.5 * HIT
        return
    assert 0.0 <= s <= s_max
    at_stop = distances(points, chain, s)
    # the reported sample is at the hit level of the reported shape ...
    assert at_stop[shape, point] <= HIT + 1e-12
    assert at_stop.min() >= 0.5 * HIT - 1e-9
    # ... and no sample came closer than half the hit level before
    assert nearest[grid < s].min(initial=np.inf) >= 0.5 * HIT - 1e-9
    # where a sample first reaches the hit level on the grid, the search has stopped
    reached = np.nonzero(nearest <= 0.5 * HIT)[0]
    if len(reached):
        assert s <= grid[reached[0]]


@pytest.mark.parametrize("seed", range(3))
def test_approach_stops_where_the_reference_says(seed):
    rng = np.random.default_rng(seed)
    dofs = get_hand("barrett").open_dofs(rng.uniform())
    chain = approach_chain("barrett", dofs)
    center = np.array([*rng.uniform(-0.06, 0.06, 2), rng.uniform(0.15, 0.25)])
    cloud, points = sphere_cloud(center, rng.uniform(0.01, 0.05), 400, rng)
    rot, trans = np.eye(3), np.zeros(3)
    s, p, q = kernels.approach_until_contact(cloud, rot, trans, chain.shapes, 0.3, HIT)
    check_against_reference(cloud, points, chain, 0.3, s, p, q)
    # the approach is the one search on its one-slide chain
    assert (s, p, q) == kernels.first_contact(cloud, rot, trans, chain, 0.3, HIT)


@pytest.mark.parametrize(
    ("hand_name", "finger", "seed", "flip"),
    [
        ("barrett", 0, 0, False),
        ("barrett", 1, 1, False),
        ("barrett", 1, 7, False),
        ("barrett", 2, 2, False),
        ("barrett", 0, 3, False),
        ("parallel_jaw", 0, 4, False),
        ("parallel_jaw", 1, 7, False),
        ("parallel_jaw", 0, 6, True),
        ("parallel_jaw", 1, 7, True),
    ],
)
def test_closing_stops_where_the_reference_says(hand_name, finger, seed, flip):
    rng = np.random.default_rng(seed)
    hand = get_hand(hand_name)
    dofs = hand.open_dofs(rng.uniform())
    chain, s_max = finger_chain(hand_name, finger, dofs)
    if flip:
        # the same motion written as a joint along -axis at negative speed
        chain = chain._replace(axes=-chain.axes, q0=-chain.q0, speeds=-chain.speeds)
    # an object between the fingers, in front of the palm
    center = np.array([*rng.uniform(-0.02, 0.02, 2), rng.uniform(0.04, 0.09)])
    cloud, points = sphere_cloud(center, rng.uniform(0.01, 0.03), 400, rng)
    assert distances(points, chain, 0.0).min() > HIT  # starts clear
    s, p, q = kernels.first_contact(cloud, np.eye(3), np.zeros(3), chain, s_max, HIT)
    check_against_reference(cloud, points, chain, s_max, s, p, q)


def test_the_search_does_no_more_work_than_measured():
    """The work of fixed searches (heap pops, distance queries): a change that makes the search
    do more (a looser bound, a worse culling, a finer step) fails here."""
    rng = np.random.default_rng(7)
    cloud, _ = sphere_cloud(np.array([0.01, -0.005, 0.07]), 0.03, 20000, rng)
    rot, trans = np.eye(3), np.zeros(3)
    hand = get_hand("barrett")
    dofs = hand.open_dofs(0.5)
    counts = np.zeros(kernels.N_COUNTS, dtype=np.int64)
    chain = approach_chain("barrett", dofs)
    # the hand backed off 10 cm: the approach has some way to go
    s, _, _ = kernels.first_contact_counted(
        cloud, rot, np.array([0.0, 0.0, -0.1]), chain, 0.3, HIT_EPS, counts
    )
    assert np.isfinite(s)
    approach = counts.copy()
    counts[:] = 0
    for finger in range(3):
        chain, s_max = finger_chain("barrett", finger, dofs)
        kernels.first_contact_counted(cloud, rot, trans, chain, s_max, HIT_EPS, counts)
    closing = counts
    assert approach[kernels.POPS] <= 1.05 * APPROACH_POPS
    assert approach[kernels.QUERIES] <= 1.05 * APPROACH_QUERIES
    assert closing[kernels.POPS] <= 1.05 * CLOSING_POPS
    assert closing[kernels.QUERIES] <= 1.05 * CLOSING_QUERIES
    assert closing[kernels.REFINE_QUERIES] <= 1.05 * CLOSING_REFINE


def breakaway_reference(hand, cloud, rot, trans, dofs):
    """GraspIt!'s autograsp written out in Python on top of the one search: every finger closes
    until a link touches (the joints up to it stop, those beyond go on) or a joint reaches its
    limit (it stops, the others go on)."""
    arrays = hand_arrays(hand)
    dofs = dofs.copy()
    links = arrays.link_poses(dofs)
    for f in arrays.fingers:
        active = [j for j in range(len(f.dofs)) if dofs[f.dofs[j]] < f.upper[j]]
        while active:
            speeds = np.zeros(len(f.dofs))
            speeds[active] = f.ratios[active] * f.speeds[active]
            chain_index, shapes = f.shapes[active[0]]
            s_max = max(min((f.upper[j] - dofs[f.dofs[j]]) / f.speeds[j] for j in active), 0.0)
            chain = kernels.Chain(
                links[f.parent], f.origins, f.kinds, f.axes, f.ratios * dofs[f.dofs], speeds,
                chain_index, shapes,
            )  # fmt: skip
            s_hit, _, q_hit = kernels.first_contact(cloud, rot, trans, chain, s_max, HIT_EPS)
            s = min(s_hit, s_max)
            for j in active:
                dofs[f.dofs[j]] = min(dofs[f.dofs[j]] + f.speeds[j] * s, f.upper[j])
            if np.isfinite(s_hit) and s_hit <= s_max:
                active = [j for j in active if j > chain_index[q_hit]]
            else:
                active = [j for j in active if dofs[f.dofs[j]] < f.upper[j] - JOINT_AT_LIMIT]
    return dofs


@pytest.mark.parametrize("hand_name", ["barrett", "parallel_jaw"])
def test_closing_every_finger_is_the_breakaway_loop(hand_name):
    hand = get_hand(hand_name)
    rng = np.random.default_rng(11)
    for _ in range(6):
        cloud, _ = sphere_cloud(
            np.array([*rng.uniform(-0.03, 0.03, 2), rng.uniform(0.04, 0.1)]),
            rng.uniform(0.01, 0.04),
            3000,
            rng,
        )
        dofs = hand.open_dofs(rng.uniform())
        pose = np.eye(4)
        got = close_fingers(hand, SimpleNamespace(**cloud._asdict()), pose, dofs)
        want = breakaway_reference(hand, cloud, np.eye(3), np.zeros(3), dofs)
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("seed", range(6))
def test_the_search_queue_pops_the_smallest_key_with_its_entry(seed):
    # The search's 4-ary heap: random pushes and pops, many equal keys (a cell's children
    # and slid points share theirs); every pop is a smallest key present, with the entry and
    # bracket pushed with it, and nothing is lost.
    rng = np.random.default_rng(seed)
    cap = 600
    heap = (np.empty(cap), np.empty(cap, dtype=np.int64), np.empty(cap))
    size = 0
    present = {}
    next_id = 0
    for _ in range(3000):
        if size < cap and (size == 0 or rng.random() < 0.55):
            k = float(rng.integers(0, 40)) if rng.random() < 0.5 else float(rng.random() * 40)
            size = kernels._heap_push(*heap, size, k, next_id, -k)
            present[next_id] = k
            next_id += 1
        else:
            k, e, p, size = kernels._heap_pop(*heap, size)
            assert k == min(present.values())
            assert present.pop(e) == k and p == -k
        assert size == len(present)
    popped = []
    while size:
        k, e, _, size = kernels._heap_pop(*heap, size)
        assert present.pop(e) == k
        popped.append(k)
    assert popped == sorted(popped) and not present
