"""The unit of work of a grasp-evaluating run (generate, optimise) and what travels with it.

A run ships its objects once (:class:`ObjectPayload`: the resolved mesh and mass, so that a
worker neither resolves specs nor reads mesh files) in a :class:`RunContext`, and cuts its
samples into :class:`Job` s; the engines of :mod:`affordgrasp.runtime.engines` run each job
through the context's :meth:`RunContext.run` wherever they run it. A worker rebuilds each
object once, checking its mesh hash, and keeps the few it used last.
"""

from __future__ import annotations

import uuid
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa

from ..errors import InternalError
from ..hands import Hand
from ..robust import RobustSettings


@dataclass(frozen=True)
class ObjectPayload:
    """What a worker needs to rebuild a resolved object exactly.

    Attributes
    ----------
    name, category, source : str
        As the object's (:class:`~affordgrasp.objects.GraspObject`).
    density : float
        kg/m^3 (mean density).
    mesh_hash : str
        Checked again by the worker.
    vertices : (v, 3) float64 ndarray
        The prepared mesh as resolved, m.
    faces : (f, 3) int64 ndarray
    face_parts : (f,) int8 ndarray or None
        Semantic part of each face (procedural families).
    part_names : tuple of str
        The names the part labels index.
    mass : MassProperties or None
        As resolved (unit density, or a family's materials); None: uniform at ``density``.
    materials : bool
        Whether ``mass`` follows the family's per-part materials.
    """

    name: str
    category: str
    source: str
    density: float
    mesh_hash: str
    vertices: np.ndarray
    faces: np.ndarray
    face_parts: np.ndarray | None = None
    part_names: tuple[str, ...] = ()
    # the resolved mass properties, so that the workers use the same ones
    mass: object | None = None
    materials: bool = False

    @classmethod
    def from_object(cls, obj) -> ObjectPayload:
        """The payload of a resolved object.

        Parameters
        ----------
        obj : GraspObject

        Returns
        -------
        ObjectPayload
        """
        return cls(
            name=obj.name,
            category=obj.category,
            source=obj.source,
            density=float(obj.mass.density),
            mesh_hash=obj.mesh_hash,
            vertices=np.ascontiguousarray(obj.vertices, dtype=np.float64),
            faces=np.ascontiguousarray(obj.faces, dtype=np.int64),
            face_parts=getattr(obj, "face_parts", None),
            part_names=tuple(getattr(obj, "part_names", ())),
            mass=obj.mass,
            materials=bool(getattr(obj, "materials", False)),
        )

    def build(self):
        """The GraspObject again, with the same mesh bytes (checked by hash).

        Returns
        -------
        GraspObject

        Raises
        ------
        InternalError
            When the mesh arrived changed.
        """
        from ..objects import GraspObject, mass_properties, mesh_hash
        from ..objects.prepared import MeshData

        # arrays, not a trimesh.Trimesh: the worker builds one only if something needs it
        mesh = MeshData(self.vertices, self.faces, self.mesh_hash)
        digest = mesh_hash(mesh)
        if digest != self.mesh_hash:  # pragma: no cover - a transport error
            raise InternalError(f"object {self.name!r} arrived with a different mesh hash")
        return GraspObject(
            name=self.name,
            category=self.category,
            mesh=mesh,
            mass=self.mass
            if self.mass is not None
            else mass_properties(mesh.to_trimesh(), density=self.density),
            mesh_hash=digest,
            source=self.source,
            face_parts=self.face_parts,
            part_names=self.part_names,
            materials=self.materials,
        )


@dataclass(frozen=True)
class RunContext:
    """The settings every job of a run shares (sent once to each worker).

    Attributes
    ----------
    objects : tuple of ObjectPayload
        The run's objects, by index.
    hand : Hand or str
        The Hand itself, not its name: a custom hand travels to the workers as it is (a name
        would be looked up again there, and a custom hand named "barrett" replaced). A job
        resolves a name once and passes the Hand down.
    seed : int
        The run's seed.
    object_seeds : tuple of int, optional
        Each object's sample seed, by index (a run with per-object streams); None: every
        object draws from ``seed``.
    metrics, soft, depth : bool
        Metric columns, soft-finger contacts, depth images.
    volume : bool
        Compute the GWS volume (``gws_volume``; null otherwise).
    key : str
        Identifies the run, so that a worker process rebuilds its objects once per run.
    """

    objects: tuple[ObjectPayload, ...]
    # The Hand itself, not its name: a custom hand travels to the workers as it is (a name
    # would be looked up again there, and a custom hand named "barrett" replaced).
    hand: Hand | str = "barrett"
    seed: int = 0
    object_seeds: tuple[int, ...] | None = None
    metrics: bool = True
    soft: bool = False
    depth: bool = False
    volume: bool = False
    robust: RobustSettings | None = None
    key: str = field(default_factory=lambda: uuid.uuid4().hex)

    def seed_of(self, object_index: int) -> int:
        """The seed object ``object_index`` draws its samples from.

        Parameters
        ----------
        object_index : int
            Index into :attr:`objects`.

        Returns
        -------
        int
            Its entry of ``object_seeds``, or the run's seed when the run shares one stream.
        """
        if self.object_seeds is None:
            return self.seed
        return self.object_seeds[object_index]

    def run(self, job: Job) -> pa.Table:
        """Evaluate one job (in the process this context is installed in).

        Parameters
        ----------
        job : Job

        Returns
        -------
        pyarrow.Table
            One row per sample (``dataset_schema``), with ``depth_mm`` when the run renders
            depth.
        """
        from ..hands import get_hand
        from ..pipeline import evaluate_inputs, evaluate_samples

        obj = _object(self, job.object_index)  # rebuilt once per process
        seed = self.seed_of(job.object_index)
        common = {
            "hand": get_hand(self.hand),
            "soft": self.soft,
            "metrics": self.metrics,
            "volume": self.volume,
            "robust": self.robust,
        }
        if job.p0 is None:
            table = evaluate_samples(obj, job.n, seed=seed, start=job.start, **common).table
        else:
            table = evaluate_inputs(
                obj, job.p0, job.use_dir, seed=seed, sample_start=job.start, **common
            ).table
        if self.depth:
            from ..vision.depth import depth_column

            table = table.append_column(*depth_column(obj, table))
        return table


@dataclass(frozen=True)
class Job:
    """Samples ``start .. start+n-1`` of object ``object_index``.

    Attributes
    ----------
    object_index : int
        Index into :attr:`RunContext.objects`.
    start : int
        Number of the first sample.
    n : int
        Samples in the job.
    p0 : (n, 6) float ndarray or None
        Given pregrasps (the optimiser); None: the run's seeded uniform samples (the
        generator).
    use_dir : (n, 2) float ndarray or None
        Given use directions, with ``p0``.
    """

    object_index: int
    start: int
    n: int
    p0: np.ndarray | None = None
    use_dir: np.ndarray | None = None


# Per process: the current run's most recently used rebuilt objects. Bounded: a run of a
# thousand objects would otherwise keep every prepared object (its surface samples,
# acceleration structures and Embree scenes) alive in every worker. Jobs come object by
# object (shards are planned object-major), so a worker holds at most a few objects at once
# and rebuilds none of them.
_RUN_KEY: str | None = None
_OBJECTS: OrderedDict[int, object] = OrderedDict()
_KEEP_OBJECTS = 8


def _object(context: RunContext, index: int):
    global _RUN_KEY
    if _RUN_KEY != context.key:
        _RUN_KEY = context.key
        _OBJECTS.clear()
    obj = _OBJECTS.get(index)
    if obj is None:
        obj = context.objects[index].build()
        _OBJECTS[index] = obj
        while len(_OBJECTS) > _KEEP_OBJECTS:
            _OBJECTS.popitem(last=False)
    else:
        _OBJECTS.move_to_end(index)
    return obj
