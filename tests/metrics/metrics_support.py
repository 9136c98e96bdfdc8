"""Shared helpers of the metric tests: random contact sets and independent reference code.

The reference functions here are written from conventions: Metrics directly in plain numpy/scipy,
independently of the compiled kernels, so that the tests check the kernels.
"""

from __future__ import annotations

import numpy as np
import trimesh

from affordgrasp.metrics.contacts import ContactSet
from affordgrasp.objects.mass import MassProperties

SQRT2 = np.sqrt(2.0)


def ref_cone_edges(outward_normal: np.ndarray, mu: float) -> np.ndarray:
    """(8, 3) edge forces of one contact, GraspIt!'s tangent convention (conventions: Metrics)."""
    n = -np.asarray(outward_normal, dtype=float)
    n = n / np.linalg.norm(n)
    axis = np.array([0.0, 0.0, 1.0]) if abs(n[0]) > 1 - 1e-12 else np.array([1.0, 0.0, 0.0])
    t1 = np.cross(n, axis)
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(n, t1)
    t2 /= np.linalg.norm(t2)
    theta = 2 * np.pi * np.arange(8) / 8
    return n + mu * (np.cos(theta)[:, None] * t1 + np.sin(theta)[:, None] * t2)


def ref_wrenches(points, normals, mu, center, torque_scale=1.0) -> np.ndarray:
    """(6, 8k) wrench matrix built contact by contact."""
    cols = []
    mu = np.broadcast_to(np.asarray(mu, dtype=float), (len(points),))
    for p, n, m in zip(points, normals, mu, strict=True):
        for f in ref_cone_edges(n, m):
            cols.append(np.concatenate([f, np.cross(p - center, f) * torque_scale]))
    return np.array(cols).T if cols else np.zeros((6, 0))


def random_contacts(rng, k: int, radius: float = 0.05, spread: float = 0.3, mu=None):
    """k contacts on a sphere of ``radius`` with normals tilted by ``spread`` (radial ± noise)."""
    d = rng.normal(size=(k, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    points = radius * d * rng.uniform(0.6, 1.0, size=(k, 1))
    normals = d + spread * rng.normal(size=(k, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    if mu is None:
        mu = rng.uniform(0.2, 1.0, size=k)
    return ContactSet.from_arrays(points, normals, mu)


def cube_face_contacts(half: float = 0.05, mu: float = 0.5) -> ContactSet:
    """Six contacts at the face centres of a cube centred at the origin."""
    axes = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]])
    return ContactSet.from_arrays(half * axes, axes, mu)


def box_mass(extents, density: float = 1.0, center=(0.0, 0.0, 0.0)) -> MassProperties:
    """Closed-form mass properties of a solid box (independent of any mesh code)."""
    a, b, c = np.asarray(extents, dtype=float)
    volume = a * b * c
    m = density * volume
    inertia = m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    center = np.asarray(center, dtype=float)
    half = np.array([a, b, c]) / 2
    return MassProperties(
        density=density,
        volume=volume,
        mass=m,
        center_of_mass=center,
        inertia=inertia,
        r_max=float(np.linalg.norm(half)),
        bounds=np.stack([center - half, center + half]),
    )


def transform_mass(mass: MassProperties, R: np.ndarray, t: np.ndarray, s: float = 1.0):
    """Mass properties after x -> s R x + t at the same density."""
    return MassProperties(
        density=mass.density,
        volume=mass.volume * s**3,
        mass=mass.mass * s**3,
        center_of_mass=s * R @ mass.center_of_mass + t,
        inertia=s**5 * R @ mass.inertia @ R.T,
        r_max=mass.r_max * s,
        bounds=mass.bounds * s,  # not used by the metrics
    )


def rotation_about_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def fine_cylinder(radius: float, height: float, sections: int = 256, subdivisions: int = 2):
    """A cylinder from trimesh, subdivided, with its side vertices pushed back onto the
    exact cylinder so small triangles sample the curved surface (not the flat facets of the
    polygonal prism). Height is chosen by the caller close to the section width so the
    side triangles are near-isotropic."""
    mesh = trimesh.creation.cylinder(radius=radius, height=height, sections=sections)
    for _ in range(subdivisions):
        mesh = mesh.subdivide()
    v = mesh.vertices.copy()
    r = np.linalg.norm(v[:, :2], axis=1)
    side = np.abs(np.abs(v[:, 2]) - height / 2) > 1e-12
    v[side, :2] *= (radius / r[side])[:, None]
    return trimesh.Trimesh(v, mesh.faces, process=False)


def wedge_prism(angle: float, length: float = 0.05, depth: float = 0.02, segments: int = 20):
    """A triangular prism along x: an isosceles cross-section with apex angle ``angle``
    whose apex (the sharp edge) is the x axis, the solid opening towards +y."""
    half = np.tan(angle / 2) * depth
    section = np.array([[0.0, 0.0], [half, depth], [-half, depth]])  # (z, y) pairs
    xs = np.linspace(-length / 2, length / 2, segments + 1)
    verts = np.array([[x, y, z] for x in xs for (z, y) in section])
    faces = []
    for i in range(segments):
        a, b = 3 * i, 3 * (i + 1)
        for j in range(3):
            j2 = (j + 1) % 3
            faces += [[a + j, b + j, b + j2], [a + j, b + j2, a + j2]]
    faces += [[0, 2, 1], [3 * segments, 3 * segments + 1, 3 * segments + 2]]
    mesh = trimesh.Trimesh(verts, np.array(faces), process=True)
    mesh.fix_normals()
    return mesh


def folded_sheet(angle: float, spacing: float = 5e-4, nx: int = 21, ns: int = 8):
    """Two finely gridded flanks meeting at a sharp edge along x with opening ``angle``.

    An open surface (enough for U_g, which only looks at neighbourhoods): rows of vertices
    at distances 0, spacing, ..., ns * spacing from the edge on each flank. Returns the
    mesh and the indices of the faces that touch the edge.
    """
    xs = (np.arange(nx) - nx // 2) * spacing
    c, s = np.cos(angle / 2), np.sin(angle / 2)
    rows = [np.stack([xs, np.zeros(nx), np.zeros(nx)], 1)]
    for sign in (1.0, -1.0):
        for j in range(1, ns + 1):
            d = j * spacing
            rows.append(np.stack([xs, np.full(nx, d * c), np.full(nx, sign * d * s)], 1))
    verts = np.concatenate(rows)

    def vid(row, i):
        return row * nx + i

    faces, edge_faces = [], []
    for flank in (0, 1):
        chain = [0] + [1 + flank * ns + j for j in range(ns)]
        for r0, r1 in zip(chain[:-1], chain[1:], strict=True):
            for i in range(nx - 1):
                quad = [
                    [vid(r0, i), vid(r0, i + 1), vid(r1, i + 1)],
                    [vid(r0, i), vid(r1, i + 1), vid(r1, i)],
                ]
                if flank:
                    quad = [f[::-1] for f in quad]
                if r0 == 0:
                    edge_faces += [len(faces), len(faces) + 1]
                faces += quad
    return trimesh.Trimesh(verts, np.array(faces), process=False), np.array(edge_faces)
