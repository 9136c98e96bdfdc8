"""A hand is data: links with collision shapes, a kinematic tree, DOFs and a closing behaviour.

Conventions (conventions: Hands):

* The hand frame is the palm frame: the palm face lies in the plane z = 0, its centre is the
  origin, and the hand approaches along +z.
* Every link's collision geometry is a union of *sphere-swept convex cores*: a box or a
  capped cylinder grown by a ball of radius ``radius`` (a rounded box / rounded cylinder).
  Their signed distance is exact and cheap, and because every edge is rounded a dense sample
  of the object surface cannot pass between samples into a link by more than about
  ``spacing**2 / (8 * radius)`` (see ``affordgrasp.grasp.policy``).
* A joint moves its child link relative to its parent: ``T_child = T_parent @ origin @ M(q)``
  with ``M`` a rotation about ``axis`` by ``q`` (revolute) or a translation along it
  (prismatic), and ``q = ratio * dof_value`` (couplings and mirrored DOFs).
* A finger is a chain of closing DOFs (proximal first) with closing speeds. Closing moves all
  still-active DOFs of the finger together at their speeds; when a link is blocked the DOFs up
  to and including the one that drives it stop and the ones beyond keep closing
  (breakaway, as the Barrett TorqueSwitch). A finger stops when every DOF is stopped by a
  contact or its limit.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import HandError
from ..materials import MATERIALS
from ..tolerances import ORTHONORMAL

BOX = 0
CYLINDER = 1


@dataclass(frozen=True)
class Shape:
    """A sphere-swept convex core in its link's frame.

    Attributes
    ----------
    kind : str
        ``"box"`` (core half extents hx, hy, hz) or ``"cylinder"`` (core radius hx, half
        height hz, axis along the shape's z).
    half_extents : (3,) float
        The core before rounding, m.
    radius : float
        Rounding radius, m.
    pose : (4, 4) float
        The shape frame in the link frame.
    """

    kind: str
    half_extents: tuple[float, float, float]
    radius: float
    pose: np.ndarray = field(default_factory=lambda: np.eye(4))


@dataclass(frozen=True)
class Joint:
    """The joint that connects a link to its parent.

    Attributes
    ----------
    kind : str
        ``"revolute"`` or ``"prismatic"``.
    origin : (4, 4) float
        Joint frame in the parent link frame at q = 0 (m).
    axis : (3,) float
        Unit axis in the joint frame.
    dof : str
        The DOF that drives it.
    ratio : float
        q = ratio * dof_value.
    """

    kind: str
    origin: np.ndarray
    axis: np.ndarray
    dof: str
    ratio: float = 1.0


@dataclass(frozen=True)
class Link:
    """A rigid body of the hand.

    Attributes
    ----------
    name : str
        Unique within the hand.
    parent : str or None
        The parent link's name; None for the root (the palm).
    joint : Joint or None
        The joint to the parent; None for the root.
    shapes : tuple of Shape
        The link's collision and display geometry.
    material : str
        Surface material (friction with the object: :mod:`affordgrasp.materials`).
    """

    name: str
    parent: str | None
    joint: Joint | None
    shapes: tuple[Shape, ...]
    material: str


@dataclass(frozen=True)
class Dof:
    """One degree of freedom: rad for revolute, m for prismatic.

    Attributes
    ----------
    name : str
        Unique within the hand.
    lower, upper : float
        Limits, rad or m.
    role : str
        ``"pregrasp"`` (set before the approach, e.g. the spread) or ``"close"``.
    """

    name: str
    lower: float
    upper: float
    role: str  # "pregrasp" (set before the approach, e.g. the spread) or "close"


@dataclass(frozen=True)
class Finger:
    """A chain of closing DOFs (proximal first) and the speed of each while closing.

    Attributes
    ----------
    name : str
        The finger's name.
    dofs : tuple of str
        Closing DOFs, proximal first.
    speeds : tuple of float
        Relative closing speed of each DOF (the distal of the Barrett turns at 1/3).
    """

    name: str
    dofs: tuple[str, ...]
    speeds: tuple[float, ...]


@dataclass(frozen=True)
class Hand:
    """A hand: links in topological order (the root, the palm, first), DOFs and fingers.

    Attributes
    ----------
    name : str
        The hand's name (the registry key, stored in every sample row).
    links : tuple of Link
        Links, parents before children; the first is the root (the palm).
    dofs : tuple of Dof
        Degrees of freedom, in the order of a row's ``joints``.
    fingers : tuple of Finger
        Chains of closing DOFs with their closing speeds.
    pregrasp_dof : str or None
        The DOF set from the pregrasp's last parameter s ∈ [0, 1] (linearly between its
        limits), or None when the hand has none.
    description : str
        One line for listings and dataset cards.
    """

    name: str
    links: tuple[Link, ...]
    dofs: tuple[Dof, ...]
    fingers: tuple[Finger, ...]
    pregrasp_dof: str | None
    description: str = ""

    def __post_init__(self) -> None:
        validate_hand(self)

    @property
    def dof_names(self) -> list[str]:
        """Names of the DOFs, in the order of ``dofs`` (and of DOF value arrays)."""
        return [d.name for d in self.dofs]

    @property
    def link_names(self) -> list[str]:
        """Names of the links, in the order of ``links`` (root first)."""
        return [link.name for link in self.links]

    def dof_index(self, name: str) -> int:
        """Position of a DOF in the hand's DOF order.

        Parameters
        ----------
        name : str
            A DOF name.

        Returns
        -------
        int

        Raises
        ------
        ValueError
            For a name that is not a DOF of the hand.
        """
        return self.dof_names.index(name)

    def open_dofs(self, s: float = 0.0) -> np.ndarray:
        """DOF values at the pregrasp: closing DOFs at their lower limit, the pregrasp DOF at ``s``.

        Parameters
        ----------
        s : float
            Position of the pregrasp DOF between its lower (0) and upper (1) limit.

        Returns
        -------
        (n_dofs,) float64 ndarray
            rad or m.
        """
        q = np.array([d.lower for d in self.dofs], dtype=np.float64)
        if self.pregrasp_dof is not None:
            d = self.dofs[self.dof_index(self.pregrasp_dof)]
            q[self.dof_index(d.name)] = d.lower + float(s) * (d.upper - d.lower)
        return q

    def forward_kinematics(self, dof_values: np.ndarray) -> np.ndarray:
        """Pose of every link in the hand frame (:mod:`affordgrasp.hands.kinematics`).

        Parameters
        ----------
        dof_values : (n_dofs,) float ndarray
            DOF values, rad or m, in ``dof_names`` order.

        Returns
        -------
        (n_links, 4, 4) float64 ndarray
            Link frame to hand frame, m.

        Raises
        ------
        HandError
            When ``dof_values`` does not hold one value per DOF.
        """
        from .kinematics import forward_kinematics

        return forward_kinematics(self, dof_values)

    def shape_poses(self, dof_values: np.ndarray) -> np.ndarray:
        """Pose of every collision shape in the hand frame.

        Parameters
        ----------
        dof_values : (n_dofs,) float ndarray
            DOF values, rad or m.

        Returns
        -------
        (n_shapes, 4, 4) float64 ndarray
            Shape frame to hand frame, m; shapes link by link, in each link's order.
        """
        link_poses = self.forward_kinematics(dof_values)
        out = [link_poses[i] @ s.pose for i, link in enumerate(self.links) for s in link.shapes]
        return np.array(out)


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix of ``angle`` about the unit ``axis`` (right-hand rule).

    Parameters
    ----------
    axis : (3,) float ndarray
        Unit axis.
    angle : float
        Angle, rad.

    Returns
    -------
    (3, 3) float64 ndarray
    """
    x, y, z = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    c, s = np.cos(angle), np.sin(angle)
    C = 1.0 - c
    return np.array(
        [
            [c + x * x * C, x * y * C - z * s, x * z * C + y * s],
            [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
            [z * x * C - y * s, z * y * C + x * s, c + z * z * C],
        ]
    )


def transform(rotation: np.ndarray | None = None, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    """A rigid transform from a rotation and a translation.

    Parameters
    ----------
    rotation : (3, 3) float ndarray, optional
        Rotation matrix; None for the identity.
    translation : (3,) array_like of float
        Translation, m.

    Returns
    -------
    (4, 4) float64 ndarray
    """
    m = np.eye(4)
    if rotation is not None:
        m[:3, :3] = rotation
    m[:3, 3] = translation
    return m


# Hands are centimetres to decimetres long: a length beyond this is a unit mistake (mm read
# as m), and it bounds the closing search, which sweeps every link through its travel.
MAX_HAND_LENGTH_M = 1.0
# A joint turns at most one full turn either way; beyond it the sweep only repeats itself.
MAX_JOINT_TURN_RAD = 2 * np.pi
# Closing speeds are relative (the Barrett's distal joints turn at 1/3): outside
# [1 / MAX_SPEED, MAX_SPEED] a joint barely moves, and the search would crawl after it.
MAX_SPEED = 1e3


_WHY = {
    "m": "a hand is centimetres to decimetres long: check the units",
    "rad": "a joint turns at most once either way",
    "": "closing speeds are relative: the Barrett's distal joints turn at 1/3",
}


def _check_numbers(where: str, values, low: float, high: float, unit: str = "m") -> None:
    """Refuse a number of a hand that is not finite or lies outside [low, high] ``unit``."""
    for x in np.ravel(np.asarray(values, dtype=np.float64)):
        if not (np.isfinite(x) and low <= x <= high):
            raise HandError(
                f"{where} must be a finite number in [{low:g}, {high:g}]{' ' * bool(unit)}"
                f"{unit}, got {x:g} ({_WHY[unit]})"
            )


def validate_hand(hand: Hand) -> None:
    """Check a hand description once, with messages that name the problem.

    Every number must be finite and within its range: lengths (half extents, rounding
    radii, translations) within :data:`MAX_HAND_LENGTH_M`, a joint's travel (ratio × the
    limits of its DOF) within one turn or that length, closing speeds within
    [1 / :data:`MAX_SPEED`, :data:`MAX_SPEED`].

    Parameters
    ----------
    hand : Hand
        The hand; a problem raises :class:`~affordgrasp.errors.HandError`.
    """
    names = [link.name for link in hand.links]
    if len(set(names)) != len(names):
        raise HandError(f"hand {hand.name!r}: link names must be unique, got {names}")
    dof_names = [d.name for d in hand.dofs]
    limits = {d.name: (d.lower, d.upper) for d in hand.dofs}
    length = MAX_HAND_LENGTH_M
    for link in hand.links:
        for s in link.shapes:
            where = f"link {link.name!r}: a shape's"
            _check_numbers(f"{where} half extents", s.half_extents, 0.0, length)
            _check_numbers(f"{where} rounding radius", s.radius, 0.0, length)
        if link.joint is not None:
            j = link.joint
            travel, unit = (MAX_JOINT_TURN_RAD, "rad") if j.kind == "revolute" else (length, "m")
            _check_numbers(
                f"link {link.name!r}: the joint's travel (ratio {j.ratio:g} × the limits of "
                f"{j.dof!r})",
                np.multiply(j.ratio, limits.get(j.dof, 0.0)),
                -travel,
                travel,
                unit,
            )
    seen: set[str] = set()
    for i, link in enumerate(hand.links):
        if link.material not in MATERIALS:
            raise HandError(
                f"link {link.name!r}: unknown material {link.material!r} (known: {MATERIALS})"
            )
        for s in link.shapes:
            if s.kind not in ("box", "cylinder"):
                raise HandError(f"link {link.name!r}: shape kind must be 'box' or 'cylinder'")
            if s.radius <= 0 or min(s.half_extents) < 0:
                raise HandError(
                    f"link {link.name!r}: shapes need a rounding radius > 0 and half extents >= 0"
                )
        if i == 0:
            if link.parent is not None or link.joint is not None:
                raise HandError("the first link must be the root (no parent, no joint)")
        else:
            if link.parent not in seen:
                raise HandError(
                    f"link {link.name!r}: parent {link.parent!r} must be listed before it"
                )
            if link.joint is None or link.joint.dof not in dof_names:
                raise HandError(f"link {link.name!r}: needs a joint driven by a known DOF")
            if link.joint.kind not in ("revolute", "prismatic"):
                raise HandError(f"link {link.name!r}: joint kind must be revolute or prismatic")
        seen.add(link.name)
    for link in hand.links:
        frames = [("shape pose", sh.pose) for sh in link.shapes]
        if link.joint is not None:
            frames.append(("joint origin", link.joint.origin))
            if not abs(np.linalg.norm(link.joint.axis) - 1.0) <= ORTHONORMAL:  # NaN too
                raise HandError(
                    f"link {link.name!r}: the joint axis must be a unit vector, got "
                    f"{np.asarray(link.joint.axis).tolist()}"
                )
        for what, m in frames:
            m = np.asarray(m, dtype=np.float64)
            r = m[:3, :3] if m.shape == (4, 4) else None
            if r is None or not (
                np.allclose(r @ r.T, np.eye(3), atol=ORTHONORMAL)
                and np.linalg.det(r) > 0
                and np.allclose(m[3], [0, 0, 0, 1])
            ):
                raise HandError(f"link {link.name!r}: the {what} must be a rigid 4x4 transform")
            where = f"link {link.name!r}: the {what}'s translation"
            _check_numbers(where, m[:3, 3], -MAX_HAND_LENGTH_M, MAX_HAND_LENGTH_M)
    for d in hand.dofs:
        if not d.lower <= d.upper:
            raise HandError(f"DOF {d.name!r}: lower limit {d.lower} > upper limit {d.upper}")
    # The closing search sweeps each finger as one chain of links, hung from a link that no
    # closing DOF moves: check the hand has that form.
    driven: dict[str, list[str]] = {}
    for link in hand.links:
        if link.joint is not None:
            driven.setdefault(link.joint.dof, []).append(link.name)
    parent_of = {link.name: link.parent for link in hand.links}
    closing = {name for f in hand.fingers for name in f.dofs}
    for f in hand.fingers:
        chain = []
        for name in f.dofs:
            links = driven.get(name, [])
            if len(links) != 1:
                raise HandError(
                    f"finger {f.name!r}: closing DOF {name!r} must drive exactly one link, "
                    f"it drives {links or 'none'} (mirror a jaw with a finger of its own)"
                )
            chain.append(links[0])
        for a, b in zip(chain, chain[1:], strict=False):
            if parent_of[b] != a:
                raise HandError(
                    f"finger {f.name!r}: link {b!r} must hang from {a!r}, the link of the "
                    "previous closing DOF"
                )
        ancestor = parent_of[chain[0]]
        while ancestor is not None:
            joint = hand.links[hand.link_names.index(ancestor)].joint
            if joint is not None and joint.dof in closing:
                raise HandError(
                    f"finger {f.name!r} hangs from {ancestor!r}, which a closing DOF "
                    f"({joint.dof!r}) moves; fingers must hang from links that stay put"
                )
            ancestor = parent_of[ancestor]
    for f in hand.fingers:
        if len(f.dofs) != len(f.speeds) or not f.dofs:
            raise HandError(f"finger {f.name!r}: needs one speed per closing DOF")
        for name in f.dofs:
            if name not in dof_names:
                raise HandError(f"finger {f.name!r}: unknown DOF {name!r}")
        for v in f.speeds:  # a joint a million times slower never reaches its limit: a hang
            _check_numbers(f"finger {f.name!r}: a closing speed", v, 1 / MAX_SPEED, MAX_SPEED, "")
    if hand.pregrasp_dof is not None and hand.pregrasp_dof not in dof_names:
        raise HandError(f"pregrasp DOF {hand.pregrasp_dof!r} is not a DOF of the hand")
