"""Object specs (conventions: Objects): families, family:seed, mesh paths; identity, caching."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import types
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import trimesh

import affordgrasp
import affordgrasp.objects as objects
from affordgrasp.errors import InputError, MeshError
from affordgrasp.objects import GraspObject, load_object, mesh_hash
from affordgrasp.objects import resolve as resolve_module
from affordgrasp.rays.mesh import mesh_caster


@dataclass(frozen=True)
class FakeFamily:
    name: str
    category: str
    description: str


def fake_families() -> types.SimpleNamespace:
    """A stand-in for objects.families: boxes whose length depends on the seed."""
    calls = []

    def make_family(name: str, seed: int = 0, *, materials: bool = False) -> trimesh.Trimesh:
        calls.append((name, seed))
        return trimesh.creation.box(extents=(0.1 + 0.01 * seed, 0.02, 0.01))

    return types.SimpleNamespace(
        FAMILIES={
            "knife": FakeFamily("knife", "blade", "a knife"),
            "meat_cleaver": FakeFamily("meat_cleaver", "blade", "a cleaver"),
        },
        make_family=make_family,
        calls=calls,
    )


@pytest.fixture
def fake(monkeypatch, tmp_path):
    families = fake_families()
    monkeypatch.setattr(resolve_module, "_families", lambda: families)
    # the stand-ins must neither come from nor go to the cache of prepared families
    monkeypatch.setenv("AFFORDGRASP_CACHE_DIR", str(tmp_path / "cache"))
    resolve_module._resolve_family.cache_clear()
    yield families
    resolve_module._resolve_family.cache_clear()


@pytest.fixture
def box_file(tmp_path) -> Path:
    path = tmp_path / "part.stl"
    trimesh.creation.box(extents=(0.1, 0.2, 0.3)).export(path)
    return path


def test_mesh_hash_is_stable_and_documented():
    mesh = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
        [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        process=False,
    )
    # The documented recipe, and a value fixed once so that any change is noticed.
    recipe = hashlib.sha256(
        np.asarray(mesh.vertices, "<f8").tobytes() + np.asarray(mesh.faces, "<i8").tobytes()
    ).hexdigest()
    assert mesh_hash(mesh) == recipe
    assert mesh_hash(mesh) == "0a6d4e58f2c49f46b948f61a6a8df6ddd1c60c7f296912361823643e586f5bbd"
    assert mesh_hash(mesh.copy()) == mesh_hash(mesh)


def test_mesh_hash_is_sensitive():
    mesh = trimesh.creation.box()
    nudged = mesh.copy()
    nudged.vertices[0, 0] += 1e-12
    reordered = trimesh.Trimesh(mesh.vertices, np.roll(mesh.faces, 1, axis=1), process=False)
    hashes = {mesh_hash(mesh), mesh_hash(nudged), mesh_hash(reordered)}
    assert len(hashes) == 3


def test_mesh_path_resolves(box_file):
    for spec in (box_file, str(box_file)):
        obj = load_object(spec)
        assert isinstance(obj, GraspObject)
        assert obj.name == "part.stl"
        assert obj.category == "mesh"
        assert obj.source == str(box_file.resolve())
        assert obj.mesh.is_watertight
        assert obj.mass.volume == pytest.approx(0.006, rel=1e-6)
        assert obj.mass.density == 1.0
        assert obj.mesh_hash == mesh_hash(obj.mesh)
    assert load_object(box_file).mesh_hash == load_object(str(box_file)).mesh_hash


def test_mesh_path_options(box_file):
    obj = load_object(box_file, units="in", density=1000.0)
    assert obj.mesh.extents.max() == pytest.approx(0.3 * 0.0254)
    assert obj.mass.mass == pytest.approx(1000.0 * 0.006 * 0.0254**3, rel=1e-5)
    assert load_object(box_file, size_m=0.6).mesh.extents.max() == pytest.approx(0.6)
    with pytest.raises(InputError, match="density"):
        load_object(box_file, density=-1.0)


def test_family_grammar(fake):
    default = load_object("knife")
    assert default.name == "knife:0"
    assert default.category == "blade"
    assert default.source == "family"
    assert load_object("knife:0") is default  # cached
    assert load_object(" Knife ") is default
    seven = load_object("knife:7")
    assert seven.name == "knife:7"
    assert seven.mesh.extents.max() == pytest.approx(0.17)
    assert seven.mesh_hash != default.mesh_hash
    assert load_object("meat-cleaver:2").name == "meat_cleaver:2"
    assert load_object("knife:007") is load_object("knife:7")
    assert fake.calls == [("knife", 0), ("knife", 7), ("meat_cleaver", 2)]


def test_family_density_and_size(fake):
    light = load_object("knife:1")
    heavy = load_object("knife:1", density=2.0)
    assert heavy is not light
    assert heavy.mass.mass == pytest.approx(2.0 * light.mass.mass)
    assert heavy.mesh_hash == light.mesh_hash
    # A family keeps its real size: rescaling it would give other geometry the same name.
    with pytest.raises(InputError, match="mesh files only"):
        load_object("knife:1", size_m=0.22)


@pytest.mark.parametrize(
    "spec", ["knife:x", "knife:-1", "knife:", "knife:1.5", "knife:+3", "knife:²"]
)
def test_bad_seed(fake, spec):
    with pytest.raises(InputError, match="seed after ':' must be a non-negative integer"):
        load_object(spec)


def test_unknown_name_lists_the_families(fake, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match=r"unknown object 'spoon'.*knife, meat_cleaver.*path"):
        load_object("spoon")
    with pytest.raises(InputError, match="unknown object 'spoon:3'"):
        load_object("spoon:3")
    with pytest.raises(InputError, match="does-not-exist.obj"):
        load_object(tmp_path / "does-not-exist.obj")
    with pytest.raises(InputError, match="empty"):
        load_object("  ")
    with pytest.raises(InputError, match="int"):
        load_object(42)  # type: ignore[arg-type]


def test_family_name_wins_over_a_file_of_that_name(fake, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "knife").write_text("not a mesh")
    assert load_object("knife").source == "family"
    with pytest.raises(MeshError, match="unsupported mesh format"):
        load_object("./knife")


def test_resolved_object_passes_through(box_file):
    obj = load_object(box_file, density=500.0)
    assert load_object(obj) is obj
    assert load_object(obj, density=500.0) is obj
    other = load_object(obj, density=1000.0)
    assert other.mesh is obj.mesh and other.mass.mass == pytest.approx(2 * obj.mass.mass)
    with pytest.raises(InputError, match="already resolved"):
        load_object(obj, size_m=0.1)


def test_without_families_every_spec_is_a_path(monkeypatch, box_file):
    def missing():
        raise ImportError("no families")

    monkeypatch.setattr(resolve_module, "_families", missing)
    monkeypatch.setattr(resolve_module, "_families_installed", lambda: False)
    with pytest.raises(InputError, match=r"Families: \(none installed\)"):
        load_object("knife")
    assert load_object(box_file).name == "part.stl"


@pytest.fixture
def real_families():
    # the registry must exist: a missing one is a failure, not a skip
    from affordgrasp.objects import families

    assert families.FAMILIES, "objects.families defines no FAMILIES"
    resolve_module._resolve_family.cache_clear()
    return families


def test_built_in_families_resolve(real_families):
    names = objects.list_families()
    assert names == sorted(real_families.FAMILIES)
    assert "knife" in names
    obj = load_object("knife")
    assert obj.name == "knife:0"
    assert obj.category == real_families.FAMILIES["knife"].category
    assert obj.mesh.is_watertight and obj.mass.volume > 0
    assert load_object("knife:0") is obj
    assert objects.make_family is real_families.make_family
    assert objects.FAMILIES is real_families.FAMILIES
    again = resolve_module._resolve_family.__wrapped__("knife", 0, 1.0, False, None, None)
    assert again.mesh_hash == obj.mesh_hash  # deterministic, not only cached


def test_family_aliases_resolve_to_the_family():
    assert load_object("cleaver:2").name == "meat_cleaver:2"


# The folder that holds the package under test (site-packages for an installed copy).
SRC = str(Path(affordgrasp.__file__).resolve().parents[1])

FACES_AT = """
import json, sys
import numpy as np
from affordgrasp.objects import load_object
obj = load_object({spec!r})
obj.mesh_data  # the derived geometry, from the cache
points, normals = (np.array(a) for a in json.loads(sys.stdin.read()))
faces = obj.faces_at(points, normals)
print(json.dumps({{"faces": faces.tolist(), "modules": sorted(sys.modules)}}))
"""


def test_faces_at_on_a_miss_is_trimeshs_closest_face_without_importing_trimesh():
    spec = "knife:3"
    obj = load_object(spec)  # builds the cache entries the subprocess loads
    mesh = obj.mesh_data
    # points on the blade's edges, with normals along the edge's bisector and tilted: some
    # rays start outside and miss the thin edge
    rng = np.random.default_rng(0)
    pairs = mesh.face_adjacency[np.abs(mesh.face_adjacency_angles) > 2.0]
    edges = mesh.face_adjacency_edges[np.abs(mesh.face_adjacency_angles) > 2.0]
    pick = rng.integers(0, len(pairs), 200)
    t = rng.random((200, 1))
    points = mesh.vertices[edges[pick, 0]] * (1 - t) + mesh.vertices[edges[pick, 1]] * t
    bisector = mesh.face_normals[pairs[pick, 0]] + mesh.face_normals[pairs[pick, 1]]
    normals = bisector + 0.5 * rng.normal(size=bisector.shape)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    rays = mesh_caster(mesh).intersects_first(points + 5e-4 * normals, -normals)
    missed = rays < 0
    assert missed.sum() >= 5  # the test is about misses
    expected = np.array(rays, dtype=np.int64)
    expected[missed] = trimesh.proximity.closest_point(obj.mesh, points[missed])[2]

    proc = subprocess.run(
        [sys.executable, "-c", FACES_AT.format(spec=spec)],
        input=json.dumps([points.tolist(), normals.tolist()]),
        capture_output=True,
        text=True,
        check=False,
        env={
            "PYTHONPATH": SRC,
            "PATH": "/usr/bin:/bin",
            "AFFORDGRASP_CACHE_DIR": os.environ["AFFORDGRASP_CACHE_DIR"],
        },
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert report["faces"] == expected.tolist()
    for name in ("trimesh", "scipy.spatial"):
        assert name not in report["modules"], name
