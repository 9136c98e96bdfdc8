import numpy as np
import trimesh

from affordgrasp.grasp import kernels
from affordgrasp.objects import GraspObject, mass_properties, mesh_hash, prepare_mesh


def as_object(mesh: trimesh.Trimesh, name: str = "test") -> GraspObject:
    mesh = prepare_mesh(mesh, source=name)
    return GraspObject(name, "mesh", mesh, mass_properties(mesh), mesh_hash(mesh), "test")


def shape_sdf(points: np.ndarray, pose: np.ndarray, kind: int, half, radius: float) -> np.ndarray:
    """Signed distance of hand-frame points to one rounded shape, written independently of
    the compiled kernels (plain numpy) so the tests check them."""
    q = (points - pose[:3, 3]) @ pose[:3, :3]
    h = np.asarray(half)
    if kind == kernels.BOX:
        d = np.abs(q) - h
        return np.linalg.norm(np.maximum(d, 0), axis=1) + np.minimum(d.max(axis=1), 0) - radius
    dr = np.linalg.norm(q[:, :2], axis=1) - h[0]
    dz = np.abs(q[:, 2]) - h[2]
    outside = np.hypot(np.maximum(dr, 0), np.maximum(dz, 0))
    return outside + np.minimum(np.maximum(dr, dz), 0) - radius
