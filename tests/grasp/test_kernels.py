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
# measured. Bounding a fine cell's points by the flat cylinder of its best-fit plane instead
# of its sphere (kernels.flat_cell_sdf_at, _chain_touch's flat) took the approach from 1585
# pops and queries to 467 and the closing from 2544 pops and 2694 queries to 2026 and 2176
# (refinement 104 -> 103) on this 3 cm sphere; splitting each fine cell's points into 2 x 2
# x 2 sub-cells, released one level at a time, to 276 (approach) and 1042 pops and 1192
# queries (closing; refinement 106); the closing's second safe step (the sdf's convexity
# along the motion's velocity, _chain_touch) to 891 pops and 1041 queries (refinement 105).
APPROACH_POPS = 276
APPROACH_QUERIES = 276
CLOSING_POPS = 891
CLOSING_QUERIES = 1041
CLOSING_REFINE = 105


def sphere_cloud(center, radius, n, rng):
    """A SampleCloud of n points on a sphere (object frame = hand frame here)."""
    v = rng.normal(size=(n, 3))
    points = center + radius * v / np.linalg.norm(v, axis=1, keepdims=True)
    order, fine, coarse, sub = group_into_cells(points)
    p = np.ascontiguousarray(points[order])
    return kernels.SampleCloud(p, *fine, *coarse, *sub), p


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
    # the approach is the one search on its one-slide chain
    s, p, q = kernels.first_contact(cloud, rot, trans, chain, 0.3, HIT)
    check_against_reference(cloud, points, chain, 0.3, s, p, q)


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


def _query(chain, frames, s, point, radius=0.0, flat=None):
    """_chain_touch for a point (radius 0), a cell's sphere or a flat cell, as the search
    asks it: (distance, safe step)."""
    o0 = (chain.base @ chain.origins[0])[:3, 3]
    r = np.linalg.norm(point - o0) + radius
    trig = np.empty((len(chain.q0), 2))
    kernels._set_trig(s, chain, trig)
    half = 0.5 * HIT
    if flat is None:
        d, _, step = kernels._chain_touch(*point, s, r, chain, frames, half + radius,
                                          HIT + radius, radius, trig, False, 0.0, 0.0, 0.0,
                                          0.0, 0.0)  # fmt: skip
        return d - radius, step
    normal, thick, spread = flat
    d, _, step = kernels._chain_touch(*point, s, r, chain, frames, half, HIT + radius, radius,
                                      trig, True, *normal, thick, spread)  # fmt: skip
    return d, step


@pytest.mark.parametrize("seed", range(3))
def test_every_step_keeps_every_point_clear_of_half_the_hit_level(seed):
    # The safe step of a distance query (_chain_touch: the larger of a speed bound and the
    # bound d + h g.u - A h^2 / 2 from the sdf's convexity, the motion's velocity u and a
    # bound A on its acceleration) against the reference distances on a dense grid over the
    # step: no point of the query (a point, every point of a cell's ball or of a flat cell)
    # comes closer than half the hit level to a moving link (so one already that close gets
    # no step).
    # Points start anywhere from inside a link to a few cm away, on fingers whose first
    # joint moves or (after a breakaway) stands still.
    rng = np.random.default_rng(seed)
    hand = get_hand("barrett")
    ball = rng.normal(size=(64, 3))
    ball *= (rng.uniform(0.0, 1.0, 64) ** (1 / 3) / np.linalg.norm(ball, axis=1))[:, None]
    long_steps = 0
    for _ in range(60):
        dofs = hand.open_dofs(rng.uniform())
        chain, s_max = finger_chain("barrett", int(rng.integers(3)), dofs)
        if rng.uniform() < 0.3:
            chain = chain._replace(speeds=chain.speeds * np.array([0.0, 1.0]))
        frames = kernels._chain_frames(chain, s_max)
        s = rng.uniform(0.0, 0.8 * s_max)
        pose = shape_poses_at(chain, s)[int(rng.integers(len(chain.shape_joint)))]
        target = pose[:3, 3] + rng.normal(size=3) * rng.uniform(0.005, 0.04)
        kind = rng.integers(3)
        if kind == 0:
            points, radius, flat = target[None], 0.0, None
            d, step = _query(chain, frames, s, target)
        elif kind == 1:
            radius = rng.uniform(5e-4, 6e-3)
            points, flat = target + radius * ball, None
            d, step = _query(chain, frames, s, target, radius)
        else:
            cell, center, radius, normal, (thick, spread) = _flat_cell(rng, 40)
            points, flat = cell - center + target, (normal, thick, spread)
            d, step = _query(chain, frames, s, target, radius, flat)
        # the query's distance is a lower bound on its points' now
        assert d <= distances(points, chain, s).min() + 1e-12
        if step == 0.0:
            continue
        # the links that move (a step is about them: a point inside a link that stands
        # still stays where it is)
        moving = [np.any(chain.speeds[: j + 1] != 0.0) for j in chain.shape_joint]
        end = min(s + step, s_max)
        nearest = min(distances(points, chain, g)[moving].min() for g in np.linspace(s, end, 150))
        assert nearest >= 0.5 * HIT - 1e-12
        long_steps += end - s > 0.05
    assert long_steps >= 10


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


def _flat_cell(rng, n):
    """n points of a slightly curved, slightly rough surface patch (a 6 mm cell), its
    sphere and its flat cylinder as group_into_cells computes them."""
    u = rng.uniform(-3e-3, 3e-3, (n, 2))
    bend = rng.uniform(-40.0, 40.0)  # 1/m: radii of curvature down to 25 mm
    height = 0.5 * bend * (u**2).sum(axis=1) + rng.normal(0.0, rng.uniform(0, 2e-4), n)
    frame = Rotation.random(random_state=rng).as_matrix()
    points = np.column_stack([u, height]) @ frame.T + rng.uniform(-0.05, 0.05, 3)
    _, (_, center, radius, normal, slab), _, _ = group_into_cells(points, size=1.0)
    return points, center[0], radius[0], normal[0], slab[0]


@pytest.mark.parametrize("seed", range(4))
def test_a_flat_cells_bound_is_below_every_point_and_above_its_sphere(seed):
    # flat_cell_sdf_at's lower bound (convexity of the shape's signed distance) against the
    # exact distance of every point of the cell, written independently (grasp_support).
    rng = np.random.default_rng(seed)
    tighter = 0
    for _ in range(100):
        points, center, radius, normal, (thick, spread) = _flat_cell(rng, int(rng.integers(3, 60)))
        assert np.all(np.abs((points - center) @ normal) <= thick)
        kind = int(rng.integers(0, 2))
        half = rng.uniform(1e-3, 2e-2, 3)
        r = rng.uniform(0.0, 5e-3)
        pose = np.eye(4)
        pose[:3, :3] = Rotation.random(random_state=rng).as_matrix()
        # the shape near the cell: its surface within a few cell radii of the centre
        pose[:3, 3] = center + rng.normal(size=3) * rng.uniform(0.0, 0.03)
        bound = kernels.flat_cell_sdf_at(
            *center, pose[None], 0, np.array([kind]), half[None], np.array([r]),
            *normal, thick, spread, radius,
        )  # fmt: skip
        exact = shape_sdf(points, pose, kind, half, r)
        sphere = shape_sdf(center[None], pose, kind, half, r)[0] - radius
        assert bound <= exact.min() + 1e-12
        assert bound >= sphere - 1e-12
        tighter += bound > sphere + 0.5 * radius
    assert tighter >= 5  # the point of it: often much tighter than the sphere


def test_surface_cells_carry_their_flat_cylinders():
    from affordgrasp.grasp.policy import object_geometry
    from affordgrasp.objects import load_object

    samples = object_geometry(load_object("mug")).samples
    start = samples.cell_start
    owner = np.repeat(np.arange(len(start) - 1), np.diff(start))
    q = samples.points - samples.cell_center[owner]
    along = np.sum(q * samples.cell_normal[owner], axis=1)
    across = np.linalg.norm(q - along[:, None] * samples.cell_normal[owner], axis=1)
    np.testing.assert_allclose(np.linalg.norm(samples.cell_normal, axis=1), 1.0, atol=1e-12)
    assert np.all(np.abs(along) <= samples.cell_slab[owner, 0])
    assert np.all(across <= samples.cell_slab[owner, 1])
    assert np.all(samples.cell_slab[:, 1] <= samples.cell_radius + 1e-12)
    # a mug is mostly smooth: most of its cells are far thinner than they are wide
    assert np.median(samples.cell_slab[:, 0] / samples.cell_radius) < 0.2


def test_sub_cells_partition_each_fine_cell_and_bound_their_points():
    from affordgrasp.grasp.policy import object_geometry
    from affordgrasp.objects import load_object

    samples = object_geometry(load_object("mug")).samples
    start, sub_start = samples.cell_start, samples.sub_start
    n_sub = len(sub_start) - 1
    # every point in exactly one sub-cell, and that sub-cell in the point's fine cell
    assert np.array_equal(np.sort(samples.sub_points), np.arange(len(samples.points)))
    sub_owner = np.repeat(np.arange(n_sub), np.diff(sub_start))
    fine_of_sub = np.repeat(np.arange(len(start) - 1), np.diff(samples.cell_sub_start))
    fine_of_point = np.searchsorted(start, samples.sub_points, side="right") - 1
    assert np.array_equal(fine_of_sub[sub_owner], fine_of_point)
    assert np.all(np.diff(samples.cell_sub_start) >= 1)
    assert np.all(np.diff(samples.cell_sub_start) <= 8) and np.all(np.diff(sub_start) >= 1)
    # listed by index within a sub-cell: the samples keep their order
    same = sub_owner[1:] == sub_owner[:-1]
    assert np.all(samples.sub_points[1:][same] > samples.sub_points[:-1][same])
    # spheres and flat cylinders bound their points, and are smaller than the fine cells'
    q = samples.points[samples.sub_points] - samples.sub_center[sub_owner]
    assert np.all(np.linalg.norm(q, axis=1) <= samples.sub_radius[sub_owner])
    along = np.sum(q * samples.sub_normal[sub_owner], axis=1)
    across = np.linalg.norm(q - along[:, None] * samples.sub_normal[sub_owner], axis=1)
    assert np.all(np.abs(along) <= samples.sub_slab[sub_owner, 0])
    assert np.all(across <= samples.sub_slab[sub_owner, 1])
    assert np.all(samples.sub_radius <= samples.cell_radius[fine_of_sub] + 1e-12)
    assert np.median(samples.sub_radius) < 0.6 * np.median(samples.cell_radius)
