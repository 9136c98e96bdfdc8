"""The grasp policy GP(p0, O) (conventions: Pregrasp; paper §III-A): approach, then close.

1. The hand starts outside the object, open at its pregrasp spread, and moves along its
   approach direction until the first contact (sample points traced exactly against the
   rounded links; the hand stops with a gap of at most ``HIT_EPS``).
2. Every finger then closes independently with the breakaway behaviour of its hand model:
   its still-active joints turn together at their speeds; a contact on a link stops the joints
   up to that link and the ones beyond keep closing; a joint at its limit stops.
3. Contacts are every link within ``CONTACT_TOL`` of the object, palm included, merged per
   link (see ``merge_link_contacts``), with μ from the friction table.

Statuses, per sample:

* ``missed``: the approach passed the object without touching it (no contacts);
* ``touched``: contact made, but after closing fewer than two links touch the object;
* ``grasped``: two or more links touch the object after closing. Whether the grasp holds is
  for the metrics to say (ε > 0 is force closure).
"""

from __future__ import annotations

import functools
import logging
import time
from dataclasses import dataclass

import numpy as np

from ..caching import IdentityCache
from ..errors import InputError
from ..hands import Hand, get_hand, kinematics
from ..hands.kinematics import KinematicTree
from ..materials import DEFAULT_OBJECT_MATERIAL, friction_coefficient
from ..objects.prepared import MeshData
from ..objects.surface import SurfaceSample
from ..tolerances import CONTACT_DISTANCE_M, JOINT_AT_LIMIT, STOP_DISTANCE_M
from . import kernels
from .contacts import ContactSet
from .pregrasp import start_poses, use_points, validate_pregrasps, validate_use_directions

log = logging.getLogger(__name__)

HIT_EPS = STOP_DISTANCE_M  # m: a link stops within 0.05 mm of the surface
CONTACT_TOL = CONTACT_DISTANCE_M  # m: links within 0.2 mm touch (conventions: 0.1-0.2 mm)
MERGE_RADIUS = 3e-3  # m: contacts of one link closer than this are merged (as GraspIt!)
PATCH_ANGLE = np.deg2rad(10.0)

STATUSES = ("missed", "touched", "grasped")


@dataclass(frozen=True)
class FingerArrays:
    """One finger's closing chain, flattened for the closing kernel.

    Attributes
    ----------
    dofs : (m,) int ndarray
        DOF index of each chain joint, proximal first.
    speeds : (m,) float64 ndarray
        Closing speed of each DOF.
    upper : (m,) float64 ndarray
        Upper limit of each DOF, rad or m.
    parent : int
        Link index of the chain's parent (does not move while the finger closes).
    origins : (m, 4, 4) float64 ndarray
        Joint frames in their parent links.
    kinds : (m,) int ndarray
        Joint kinds.
    axes : (m, 3) float64 ndarray
        Unit joint axes.
    ratios : (m,) float64 ndarray
        Joint value per unit of DOF.
    shapes : tuple
        Per first active joint j0, the shapes of the links it moves (chain links >= j0): the
        chain index of each (k,) and a ShapeSet posed in their links.
    """

    dofs: np.ndarray
    speeds: np.ndarray
    upper: np.ndarray
    parent: int
    origins: np.ndarray
    kinds: np.ndarray
    axes: np.ndarray
    ratios: np.ndarray
    shapes: tuple


@dataclass(frozen=True)
class HandArrays:
    """A hand flattened for the kernels.

    Attributes
    ----------
    hand : Hand
    tree : KinematicTree
    shape_link : (s,) int ndarray
        Link index of each shape.
    shapes : ShapeSet
        Every shape, posed in its link.
    materials : tuple of str
        Per link.
    fingers : tuple of FingerArrays
    kernel : HandKernel
        The same, flattened for :func:`~affordgrasp.grasp.kernels.simulate_batch`.
    """

    hand: Hand
    tree: KinematicTree
    shape_link: np.ndarray
    shapes: kernels.ShapeSet
    materials: tuple[str, ...]
    fingers: tuple[FingerArrays, ...]
    kernel: kernels.HandKernel

    def link_poses(self, dofs: np.ndarray) -> np.ndarray:
        """Pose of every link in the hand frame (:func:`~affordgrasp.hands.kinematics.link_poses`).

        Parameters
        ----------
        dofs : (n_dofs,) float ndarray
            DOF values, rad or m (as for every method below).

        Returns
        -------
        (l, 4, 4) float64 ndarray
            Link frame to hand frame, m.
        """
        return kinematics.link_poses(np.asarray(dofs, dtype=np.float64), self.tree)

    def shape_poses(self, dofs: np.ndarray) -> np.ndarray:
        """Pose of every shape in the hand frame.

        Parameters
        ----------
        dofs : (n_dofs,) float ndarray

        Returns
        -------
        (s, 4, 4) float64 ndarray
            Shape frame to hand frame, m.
        """
        return kinematics.shape_poses(self.link_poses(dofs), self.shape_link, self.shapes.local)

    def posed_shapes(self, dofs: np.ndarray) -> kernels.ShapeSet:
        """Every shape with its hand-frame pose at ``dofs``.

        Parameters
        ----------
        dofs : (n_dofs,) float ndarray

        Returns
        -------
        ShapeSet
            The shapes' kinds, half extents and radii with their hand-frame poses.
        """
        s = self.shapes
        return kernels.ShapeSet(self.shape_poses(dofs), s.kinds, s.halves, s.radii)

    @functools.cached_property
    def link_names(self) -> np.ndarray:
        """(l,) object ndarray: the links' names, indexed by a contact's link."""
        return np.array(self.hand.link_names, dtype=object)

    @functools.cached_property
    def stretched_reach(self) -> float:
        """How far in front of the palm the open hand reaches at its most stretched, m.

        The pregrasps' start poses keep this clear of the object; three poses of the
        pregrasp DOF bound it (they cost 7 ms, about 2 % of a 250-grasp batch, once per hand).
        """
        return max(hand_reach(self.hand, self.hand.open_dofs(s)) for s in (0.0, 0.5, 1.0))

    @functools.cached_property
    def open_radius(self) -> float:
        """The largest distance from the palm origin of any point of the open hand, m (every
        pregrasp DOF value; the robust copies' back-off)."""
        radius = 0.0
        for s in (0.0, 0.25, 0.5, 0.75, 1.0):
            poses = self.shape_poses(self.hand.open_dofs(s))
            reach = (
                np.linalg.norm(poses[:, :3, 3], axis=1)
                + np.linalg.norm(self.shapes.halves, axis=1)
                + self.shapes.radii
            )
            radius = max(radius, float(reach.max()))
        return radius


_HAND_ARRAYS: IdentityCache[HandArrays] = IdentityCache()


def hand_arrays(hand: Hand) -> HandArrays:
    """The hand as flat arrays for the compiled kernels, built once per Hand object.

    Parameters
    ----------
    hand : Hand

    Returns
    -------
    HandArrays
    """
    return _HAND_ARRAYS.get(hand, lambda: _build_hand_arrays(hand))


def _build_hand_arrays(hand: Hand) -> HandArrays:
    shape_link, local, kinds, halves, radii = [], [], [], [], []
    for i, link in enumerate(hand.links):
        for s in link.shapes:
            shape_link.append(i)
            local.append(s.pose)
            kinds.append(kernels.BOX if s.kind == "box" else kernels.CYLINDER)
            halves.append(s.half_extents)
            radii.append(s.radius)
    tree = kinematics.kinematic_tree(hand)
    link_of_dof = {}
    for i, link in enumerate(hand.links):
        if link.joint is not None:
            link_of_dof.setdefault(link.joint.dof, i)
    shape_link = np.array(shape_link, dtype=np.int64)
    all_local = np.array(local, dtype=np.float64).reshape(-1, 4, 4)
    all_halves = np.array(halves, dtype=np.float64).reshape(-1, 3)
    all_kinds = np.array(kinds, dtype=np.int64)
    all_radii = np.array(radii, dtype=np.float64)
    fingers = []
    for finger in hand.fingers:
        chain = [link_of_dof[d] for d in finger.dofs]
        subsets = []
        for j0 in range(len(chain)):
            ids = np.array([s for s, li in enumerate(shape_link) if li in chain[j0:]], dtype=int)
            subsets.append(
                (
                    np.array([chain.index(shape_link[s]) for s in ids], dtype=np.int64),
                    kernels.ShapeSet(
                        np.ascontiguousarray(all_local[ids]),
                        all_kinds[ids],
                        np.ascontiguousarray(all_halves[ids]),
                        all_radii[ids],
                    ),
                )
            )
        fingers.append(
            FingerArrays(
                np.array([hand.dof_index(d) for d in finger.dofs], dtype=np.int64),
                np.array(finger.speeds, dtype=np.float64),
                np.array([hand.dofs[hand.dof_index(d)].upper for d in finger.dofs]),
                int(tree.parent[chain[0]]),
                tree.origin[chain].copy(),
                tree.kind[chain].copy(),
                tree.axis[chain].copy(),
                tree.ratio[chain].copy(),
                tuple(subsets),
            )
        )
    shapes = kernels.ShapeSet(all_local, all_kinds, all_halves, all_radii)
    return HandArrays(
        hand,
        tree,
        shape_link,
        shapes,
        tuple(link.material for link in hand.links),
        tuple(fingers),
        _hand_kernel(tree, shape_link, shapes, fingers),
    )


def _hand_kernel(tree, shape_link, shapes, fingers) -> kernels.HandKernel:
    """The fingers' arrays concatenated (offsets per finger and per first joint)."""
    subsets = [sub for f in fingers for sub in f.shapes]

    def cat(arrays, dtype, tail):
        arrays = [np.asarray(a, dtype=dtype).reshape(-1, *tail) for a in arrays]
        return np.ascontiguousarray(np.concatenate(arrays) if arrays else np.zeros((0, *tail)))

    def offsets(counts):
        return np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)

    return kernels.HandKernel(
        tree,
        shape_link,
        shapes,
        np.array([f.parent for f in fingers], dtype=np.int64),
        offsets([len(f.dofs) for f in fingers]),
        cat([f.origins for f in fingers], np.float64, (4, 4)),
        cat([f.kinds for f in fingers], np.int64, ()),
        cat([f.axes for f in fingers], np.float64, (3,)),
        cat([f.ratios for f in fingers], np.float64, ()),
        cat([f.speeds for f in fingers], np.float64, ()),
        cat([f.upper for f in fingers], np.float64, ()),
        cat([f.dofs for f in fingers], np.int64, ()),
        offsets([len(idx) for idx, _ in subsets]),
        cat([idx for idx, _ in subsets], np.int64, ()),
        kernels.ShapeSet(
            cat([sh.local for _, sh in subsets], np.float64, (4, 4)),
            cat([sh.kinds for _, sh in subsets], np.int64, ()),
            cat([sh.halves for _, sh in subsets], np.float64, (3,)),
            cat([sh.radii for _, sh in subsets], np.float64, ()),
        ),
    )


@dataclass(frozen=True)
class ObjectGeometry:
    """What the simulator needs of an object, computed once per object.

    Everything here is in the object's *centred* frame: the mesh frame shifted by ``origin``,
    the centre of the mesh's bounding box. The simulation runs in that frame and its results
    are mapped back by adding ``origin``, so an object far from its mesh origin (10 m, 1e6 m)
    is simulated on the same numbers as at the origin: no digits lost to the offset, the same
    sample grid, the same search order.

    Attributes
    ----------
    samples : SurfaceSample
        Surface samples, centred frame.
    hull_vertices : (v, 3) float64 ndarray
        Convex-hull vertices, centred frame, m.
    origin : (3,) float64 ndarray
        The centred frame's origin in the mesh frame, m.
    mesh : MeshData
        The centred mesh (for the use-point rays, cast in float32 by the ray engine).
    """

    samples: SurfaceSample
    hull_vertices: np.ndarray
    origin: np.ndarray
    mesh: MeshData


_GEOMETRY: IdentityCache[ObjectGeometry] = IdentityCache()


def object_geometry(obj) -> ObjectGeometry:
    """Surface samples and hull of an object, cached for the object's lifetime.

    Parameters
    ----------
    obj : GraspObject

    Returns
    -------
    ObjectGeometry
    """

    def build() -> ObjectGeometry:
        # computed once per machine and mesh, then loaded (objects/prepared.py)
        from ..objects.prepared import derived_geometry

        d = derived_geometry(obj)
        return ObjectGeometry(d.samples, d.hull_vertices, d.origin, d.centred)

    return _GEOMETRY.get(obj, build)


@dataclass(frozen=True)
class GraspResult:
    """The outcome of the policy for one pregrasp, in the object frame.

    Attributes
    ----------
    status : str
        One of STATUSES.
    hand_pose : (4, 4) float64 ndarray
        Final hand → object transform (palm centre at the origin), m.
    joints : (n_dofs,) float64 ndarray
        Final DOF values (rad / m), in the hand's DOF order.
    contacts : ContactSet
    """

    status: str
    hand_pose: np.ndarray
    joints: np.ndarray
    contacts: ContactSet


@dataclass(frozen=True)
class SimulationBatch:
    """Simulated grasps of one object: struct of arrays, one row per sample.

    Attributes
    ----------
    p0 : (n, 6) float64 ndarray
    use_dir : (n, 2) float64 ndarray
    status : (n,) str ndarray
    hand_pose : (n, 4, 4) float64 ndarray
        Hand → object, m.
    joints : (n, n_dofs) float64 ndarray
        rad / m.
    contacts : list of n ContactSet
    use_point : (n, 3) float64 ndarray
        m (NaN: no use point).
    use_normal : (n, 3) float64 ndarray
        Outward unit normals.
    use_triangle : (n,) int64 ndarray
        -1: no hit.
    wrist_point : (n, 3) float64 ndarray
        Palm centre, m.
    wrist_axis : (n, 3) float64 ndarray
        Approach direction.
    seconds : float
        Wall time spent simulating, s.
    """

    p0: np.ndarray
    use_dir: np.ndarray
    status: np.ndarray
    hand_pose: np.ndarray
    joints: np.ndarray
    contacts: list
    use_point: np.ndarray
    use_normal: np.ndarray
    use_triangle: np.ndarray
    wrist_point: np.ndarray
    wrist_axis: np.ndarray
    seconds: float

    def __len__(self) -> int:
        return len(self.p0)


def hand_reach(hand: Hand, dofs: np.ndarray) -> float:
    """How far in front of the palm face (z) the hand reaches at ``dofs``.

    Parameters
    ----------
    hand : Hand
    dofs : (n_dofs,) float ndarray
        rad / m.

    Returns
    -------
    float
        m.
    """
    arrays = hand_arrays(hand)
    poses = arrays.shape_poses(dofs)
    reach = 0.0
    for pose, h, r in zip(poses, arrays.shapes.halves, arrays.shapes.radii, strict=True):
        reach = max(reach, pose[2, 3] + np.linalg.norm(h) + r)
    return reach


def sample_cloud(samples: SurfaceSample) -> kernels.SampleCloud:
    """An object's surface samples as the kernels take them.

    Parameters
    ----------
    samples : SurfaceSample
        The object's surface samples and their cells.

    Returns
    -------
    SampleCloud
        The points and their coarse, fine and sub-cells (the arrays themselves, not
        copies: every field of ``SampleCloud`` is the ``SurfaceSample`` field of its name).
    """
    return kernels.SampleCloud(*(getattr(samples, name) for name in kernels.SampleCloud._fields))


def close_fingers(
    hand: Hand, samples: SurfaceSample, pose: np.ndarray, dofs: np.ndarray
) -> np.ndarray:
    """Close every finger with breakaway until it touches or reaches its limits.

    Parameters
    ----------
    hand : Hand
    samples : SurfaceSample
        The object's surface samples.
    pose : (4, 4) float64 ndarray
        Hand → object.
    dofs : (n_dofs,) float64 ndarray
        Start values.

    Returns
    -------
    (n_dofs,) float64 ndarray
        Final DOF values.
    """
    dofs = np.array(dofs, dtype=np.float64)
    kernels.close_fingers(
        sample_cloud(samples),
        np.ascontiguousarray(pose[:3, :3], dtype=np.float64),
        np.ascontiguousarray(pose[:3, 3], dtype=np.float64),
        hand_arrays(hand).kernel,
        dofs,
        HIT_EPS,
        JOINT_AT_LIMIT,
    )
    return dofs


@functools.lru_cache(maxsize=64)
def _link_mu(materials: tuple[str, ...], object_material: str) -> np.ndarray:
    """Friction coefficient of each link against the object (read-only: indexed per grasp)."""
    mu = np.array([friction_coefficient(m, object_material) for m in materials])
    mu.flags.writeable = False
    return mu


def grasp_once(
    hand: Hand,
    geom: ObjectGeometry,
    start_pose: np.ndarray,
    travel: float,
    s: float,
    object_material: str = DEFAULT_OBJECT_MATERIAL,
) -> GraspResult:
    """Run the policy for one start pose and pregrasp DOF value.

    Parameters
    ----------
    hand : Hand
    geom : ObjectGeometry
    start_pose : (4, 4) float64 ndarray
        Hand → object (mesh frame), m.
    travel : float
        Approach length to try, m.
    s : float
        Pregrasp DOF parameter in [0, 1].
    object_material : str

    Returns
    -------
    GraspResult
    """
    centred = np.array(start_pose, dtype=np.float64).reshape(1, 4, 4)
    centred[0, :3, 3] -= geom.origin
    status, poses, joints, contacts = _simulate_centred(
        hand_arrays(hand),
        geom,
        centred,
        np.array([travel], dtype=np.float64),
        np.array([s]),
        object_material,
    )
    return GraspResult(str(status[0]), poses[0], joints[0], contacts[0])


def _open_dofs(hand: Hand, s: np.ndarray) -> np.ndarray:
    """:meth:`Hand.open_dofs` of every pregrasp DOF parameter in ``s`` (n,): (n, n_dofs)."""
    q = np.tile(hand.open_dofs(0.0), (len(s), 1))
    if hand.pregrasp_dof is not None:
        j = hand.dof_index(hand.pregrasp_dof)
        d = hand.dofs[j]
        q[:, j] = d.lower + np.asarray(s, dtype=np.float64) * (d.upper - d.lower)
    return q


@dataclass(frozen=True)
class FlatGrasps:
    """Simulated grasps as flat arrays (no Python object per grasp), object frame.

    Attributes
    ----------
    poses : (n, 4, 4) float64 ndarray
        Final hand → object, m.
    joints : (n, n_dofs) float64 ndarray
        Final DOF values, rad / m.
    touched : (n,) bool ndarray
        The approach touched the object.
    offsets : (n + 1,) int64 ndarray
        Grasp i owns contact rows ``offsets[i]:offsets[i + 1]``.
    points, normals : (c, 3) float64 ndarray
        Contact points (m) and the object's outward unit normals.
    mu : (c,) float64 ndarray
        Friction coefficient of each contact.
    link : (c,) int64 ndarray
        Hand link index of each contact.
    """

    poses: np.ndarray
    joints: np.ndarray
    touched: np.ndarray
    offsets: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    mu: np.ndarray
    link: np.ndarray


def simulate_starts(
    arrays: HandArrays,
    geom: ObjectGeometry,
    starts: np.ndarray,
    travel: np.ndarray,
    s: np.ndarray,
    object_material: str = DEFAULT_OBJECT_MATERIAL,
) -> FlatGrasps:
    """The policy from given start poses, in one compiled call, as flat arrays.

    Parameters
    ----------
    arrays : HandArrays
        The hand, resolved once by the caller (:func:`hand_arrays`).
    geom : ObjectGeometry
        The object's simulation geometry (:func:`object_geometry`).
    starts : (n, 4, 4) float64 ndarray
        Start poses, hand → the *centred* frame of ``geom`` (mesh frame minus
        ``geom.origin``), m.
    travel : (n,) float64 ndarray
        Approach length to try, m.
    s : (n,) float64 ndarray
        Pregrasp DOF parameters in [0, 1].
    object_material : str
        The object's surface material (friction).

    Returns
    -------
    FlatGrasps
        Poses and contacts in the object's mesh frame.
    """
    samples = geom.samples
    joints = _open_dofs(arrays.hand, s)
    poses, touched, offsets, point, shape, normal = kernels.simulate_batch(
        sample_cloud(samples),
        samples.normals,
        samples.sharp,
        np.ascontiguousarray(starts, dtype=np.float64),
        np.ascontiguousarray(travel, dtype=np.float64),
        joints,
        arrays.kernel,
        HIT_EPS,
        JOINT_AT_LIMIT,
        CONTACT_TOL,
        MERGE_RADIUS,
        np.cos(PATCH_ANGLE),
    )
    poses[:, :3, 3] += geom.origin
    link = arrays.shape_link[shape]
    points = samples.points[point] + geom.origin
    mu = _link_mu(arrays.materials, object_material)[link]
    return FlatGrasps(poses, joints, touched, offsets, points, normal, mu, link)


def pregrasp_starts(
    arrays: HandArrays, geom: ObjectGeometry, p0: np.ndarray, placing: ObjectGeometry | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Start poses (centred frame of ``geom``) and approach lengths of pregrasps.

    Parameters
    ----------
    arrays : HandArrays
        The hand (:func:`hand_arrays`); the starts keep its stretched reach clear.
    geom : ObjectGeometry
    p0 : (n, 6) float64 ndarray
        Valid pregrasps.
    placing : ObjectGeometry, optional
        The geometry whose hull places the pregrasps (``simulate(..., frame=)``), in the same
        mesh frame as ``geom``; None: ``geom`` itself.

    Returns
    -------
    starts : (n, 4, 4) float64 ndarray
        Hand → centred frame of ``geom``, m.
    travel : (n,) float64 ndarray
        m.
    """
    # The hand's reach depends on the pregrasp DOF; the fully-stretched bound is used for all.
    reach = arrays.stretched_reach
    if placing is None:
        return start_poses(p0, geom.hull_vertices, reach)
    starts, travel = start_poses(p0, placing.hull_vertices, reach)
    starts[:, :3, 3] += placing.origin - geom.origin  # its centred frame to geom's
    return starts, travel


def _simulate_centred(
    arrays: HandArrays,
    geom: ObjectGeometry,
    starts: np.ndarray,
    travel: np.ndarray,
    s: np.ndarray,
    object_material: str,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list]:
    """The policy for start poses in the centred frame of ``geom``, in one compiled call;
    poses and contacts returned in the object frame."""
    flat = simulate_starts(arrays, geom, starts, travel, s, object_material)
    link, points, normal, mu = flat.link, flat.points, flat.normals, flat.mu
    names = arrays.link_names[link]
    touched = flat.touched
    n = len(starts)
    status = np.empty(n, dtype=object)
    contacts = []
    bounds = flat.offsets.tolist()
    for i in range(n):
        a, b = bounds[i], bounds[i + 1]
        if not touched[i]:
            status[i] = "missed"
            contacts.append(ContactSet.empty())
            continue
        # two or more links touching: grasped (whether it holds is for the metrics)
        status[i] = "grasped" if len(set(link[a:b].tolist())) >= 2 else "touched"
        contacts.append(ContactSet(points[a:b], normal[a:b], mu[a:b], names[a:b]))
    return status, flat.poses, flat.joints, contacts


def simulate(
    obj,
    p0,
    use_dir=None,
    *,
    hand: Hand | str = "barrett",
    object_material: str = DEFAULT_OBJECT_MATERIAL,
    frame=None,
) -> SimulationBatch:
    """Simulate the policy for a batch of pregrasps on one object.

    Parameters
    ----------
    obj : GraspObject
        See :func:`affordgrasp.objects.load_object`.
    p0 : (n, 6) array_like of float
        Pregrasps in [-1, 1]^5 x [0, 1].
    use_dir : (n, 2) array_like of float, optional
        Use directions in [-1, 1]^2; None: no use point (NaN).
    hand : Hand or str
        A :class:`~affordgrasp.hands.Hand` or a name (:func:`~affordgrasp.hands.get_hand`),
        resolved here, with its arrays, once for the batch.
    object_material : str
        The object's surface material (friction).
    frame : GraspObject, optional
        The object whose geometry places the pregrasps (their start poses and approach
        lengths), in the same mesh frame as ``obj``; None: ``obj`` itself. A surface fused
        from camera views (:mod:`affordgrasp.vision.fusion`) is grasped from the poses the
        pregrasps have on the object it was seen from, so that both simulations move the
        hand alike.

    Returns
    -------
    SimulationBatch
    """
    arrays = hand_arrays(get_hand(hand))
    p0 = validate_pregrasps(p0)
    n = len(p0)
    geom = object_geometry(obj)
    if use_dir is None:
        use_dir = np.full((n, 2), np.nan)
        upts = np.full((n, 3), np.nan)
        unrm = np.full((n, 3), np.nan)
        utri = np.full(n, -1, dtype=np.int64)
    else:
        use_dir = validate_use_directions(use_dir)
        if len(use_dir) != n:
            raise InputError(f"need one use direction per pregrasp ({n}), got {len(use_dir)}")
        upts, unrm, utri = use_points(geom.mesh, obj.mass.center_of_mass - geom.origin, use_dir)
        upts += geom.origin
    started = time.perf_counter()
    placing = None if frame is None else object_geometry(frame)
    starts, travel = pregrasp_starts(arrays, geom, p0, placing)
    status, poses, joints, contacts = _simulate_centred(
        arrays, geom, starts, travel, p0[:, 5], object_material
    )
    seconds = time.perf_counter() - started
    return SimulationBatch(
        p0,
        use_dir,
        status,
        poses,
        joints,
        contacts,
        upts,
        unrm,
        utri,
        poses[:, :3, 3].copy(),
        poses[:, :3, 2].copy(),
        seconds,
    )
