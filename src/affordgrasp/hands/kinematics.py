"""Forward kinematics of a hand, compiled: the one implementation the package uses.

:meth:`Hand.forward_kinematics <affordgrasp.hands.model.Hand.forward_kinematics>` and the
grasp kernels (approach, closing, contacts) all call :func:`link_poses`; the joint motion
and the 4 x 4 product below are the ones the closing kernel composes along a finger.
Validated against the hand's own numbers (link lengths, tripod geometry) in
``tests/hands/test_kinematics.py``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ..caching import IdentityCache
from ..errors import HandError
from ..runtime.kernel_cache import install_package_stamp

install_package_stamp()  # before the first @njit (see kernel_cache)

REVOLUTE = 0
PRISMATIC = 1


class KinematicTree(NamedTuple):
    """A hand's links as flat arrays, in topological order (the root first).

    Attributes
    ----------
    parent : (l,) int64 ndarray
        Parent link index, -1 for the root.
    origin : (l, 4, 4) float64 ndarray
        Joint frame in the parent link frame at q = 0 (m).
    axis : (l, 3) float64 ndarray
        Unit joint axis in the joint frame.
    kind : (l,) int64 ndarray
        ``REVOLUTE`` or ``PRISMATIC``.
    dof : (l,) int64 ndarray
        Index of the DOF driving the joint (-1 for the root).
    ratio : (l,) float64 ndarray
        Joint value per unit of that DOF.
    """

    parent: np.ndarray
    origin: np.ndarray
    axis: np.ndarray
    kind: np.ndarray
    dof: np.ndarray
    ratio: np.ndarray


@njit(cache=True)
def mul4_into(a, b, out):
    """out = a @ b for rigid transforms, without temporaries.

    Parameters
    ----------
    a, b : (4, 4) float64 ndarray
        Rigid transforms (the last row 0, 0, 0, 1 is assumed).
    out : (4, 4) float64 ndarray
        Written in place; must not alias ``a`` or ``b``.
    """
    for i in range(4):
        for j in range(4):
            out[i, j] = (
                a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j] + a[i, 3] * b[3, j]
            )


@njit(cache=True)
def joint_motion_into(kind, axis, q, mot):
    """The motion of a joint at value q: rotation about or translation along its axis.

    Parameters
    ----------
    kind : int
        ``REVOLUTE`` or ``PRISMATIC``.
    axis : (3,) float64 ndarray
        Unit axis in the joint frame.
    q : float
        Joint value, rad or m.
    mot : (4, 4) float64 ndarray
        Written in place with the motion.
    """
    if kind == REVOLUTE:
        c = np.cos(q)
        sn = np.sin(q)
        C = 1.0 - c
        ax = axis[0]
        ay = axis[1]
        az = axis[2]
        mot[0, 0] = c + ax * ax * C
        mot[0, 1] = ax * ay * C - az * sn
        mot[0, 2] = ax * az * C + ay * sn
        mot[1, 0] = ay * ax * C + az * sn
        mot[1, 1] = c + ay * ay * C
        mot[1, 2] = ay * az * C - ax * sn
        mot[2, 0] = az * ax * C - ay * sn
        mot[2, 1] = az * ay * C + ax * sn
        mot[2, 2] = c + az * az * C
        mot[0, 3] = 0.0
        mot[1, 3] = 0.0
        mot[2, 3] = 0.0
    else:
        for a in range(3):
            for b in range(3):
                mot[a, b] = 1.0 if a == b else 0.0
            mot[a, 3] = axis[a] * q
    mot[3, 0] = 0.0
    mot[3, 1] = 0.0
    mot[3, 2] = 0.0
    mot[3, 3] = 1.0


@njit(cache=True)
def link_poses(q, tree):
    """Pose of every link in the hand frame.

    Parameters
    ----------
    q : (n_dofs,) float64 ndarray
        DOF values (rad or m), in the hand's DOF order.
    tree : KinematicTree
        The hand's links (:func:`kinematic_tree`).

    Returns
    -------
    (l, 4, 4) float64 ndarray
        Link frame to hand frame, translations in m.
    """
    n = tree.parent.shape[0]
    out = np.empty((n, 4, 4))
    mot = np.empty((4, 4))
    tmp = np.empty((4, 4))
    for i in range(n):
        if tree.parent[i] < 0:
            for a in range(4):
                for b in range(4):
                    out[i, a, b] = 1.0 if a == b else 0.0
            continue
        joint_motion_into(tree.kind[i], tree.axis[i], tree.ratio[i] * q[tree.dof[i]], mot)
        mul4_into(out[tree.parent[i]], tree.origin[i], tmp)
        mul4_into(tmp, mot, out[i])
    return out


@njit(cache=True)
def joint_poses(q, tree):
    """Pose of every link in its parent link's frame: the joint origin times its motion.

    The factors :func:`link_poses` multiplies along the chain, for a consumer that composes
    the chain itself (the MuJoCo scene of :mod:`affordgrasp.physics` sets the bodies it
    models without a joint this way).

    Parameters
    ----------
    q : (n_dofs,) float64 ndarray
        DOF values (rad or m), in the hand's DOF order.
    tree : KinematicTree
        The hand's links (:func:`kinematic_tree`).

    Returns
    -------
    (l, 4, 4) float64 ndarray
        Link frame to parent link frame, translations in m; the identity for the root.
    """
    n = tree.parent.shape[0]
    out = np.empty((n, 4, 4))
    mot = np.empty((4, 4))
    for i in range(n):
        if tree.parent[i] < 0:
            for a in range(4):
                for b in range(4):
                    out[i, a, b] = 1.0 if a == b else 0.0
            continue
        joint_motion_into(tree.kind[i], tree.axis[i], tree.ratio[i] * q[tree.dof[i]], mot)
        mul4_into(tree.origin[i], mot, out[i])
    return out


@njit(cache=True)
def shape_poses(links, shape_link, shape_local):
    """Pose of every shape from the link poses.

    Parameters
    ----------
    links : (l, 4, 4) float64 ndarray
        Link poses (:func:`link_poses`).
    shape_link : (s,) int64 ndarray
        The link each shape belongs to.
    shape_local : (s, 4, 4) float64 ndarray
        Shape frame in its link frame.

    Returns
    -------
    (s, 4, 4) float64 ndarray
        Shape frame to hand frame.
    """
    out = np.empty((shape_link.shape[0], 4, 4))
    for s in range(shape_link.shape[0]):
        mul4_into(links[shape_link[s]], shape_local[s], out[s])
    return out


_TREES: IdentityCache[KinematicTree] = IdentityCache()


def kinematic_tree(hand) -> KinematicTree:
    """The hand's :class:`KinematicTree`, built once per Hand object.

    Parameters
    ----------
    hand : Hand
        The hand.

    Returns
    -------
    KinematicTree
        Cached by the hand's identity.
    """
    return _TREES.get(hand, lambda: _build_tree(hand))


def _build_tree(hand) -> KinematicTree:
    names = hand.link_names
    n = len(hand.links)
    parent = np.full(n, -1, dtype=np.int64)
    origin = np.tile(np.eye(4), (n, 1, 1))
    axis = np.zeros((n, 3))
    kind = np.zeros(n, dtype=np.int64)
    dof = np.full(n, -1, dtype=np.int64)
    ratio = np.zeros(n)
    for i, link in enumerate(hand.links):
        if link.joint is None:
            continue
        j = link.joint
        parent[i] = names.index(link.parent)
        origin[i] = j.origin
        axis[i] = np.asarray(j.axis, dtype=np.float64) / np.linalg.norm(j.axis)
        kind[i] = REVOLUTE if j.kind == "revolute" else PRISMATIC
        dof[i] = hand.dof_index(j.dof)
        ratio[i] = j.ratio
    return KinematicTree(parent, origin, axis, kind, dof, ratio)


def forward_kinematics(hand, dof_values) -> np.ndarray:
    """Pose of every link of ``hand`` in the hand frame at ``dof_values``.

    Parameters
    ----------
    hand : Hand
        The hand.
    dof_values : (n_dofs,) array_like of float
        DOF values (rad or m), in ``hand.dof_names`` order.

    Returns
    -------
    (n_links, 4, 4) float64 ndarray
        Link frame to hand frame, translations in m.
    """
    q = np.asarray(dof_values, dtype=np.float64)
    if q.shape != (len(hand.dofs),):
        raise HandError(f"hand {hand.name!r} needs {len(hand.dofs)} DOF values, got {q.shape}")
    return link_poses(np.ascontiguousarray(q), kinematic_tree(hand))
