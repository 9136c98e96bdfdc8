"""The prepared-object cache (objects/prepared.py): same bytes as a fresh build, never trusted."""

import logging

import numpy as np
import pytest
import trimesh

from affordgrasp.errors import InputError
from affordgrasp.objects import families, family_names, load_mesh, load_object, prepared, resolve
from affordgrasp.objects.resolve import GraspObject


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache directory; the in-process family cache emptied around the test."""
    monkeypatch.setenv("AFFORDGRASP_CACHE_DIR", str(tmp_path))
    resolve._resolve_family.cache_clear()
    yield tmp_path / "objects"
    resolve._resolve_family.cache_clear()


def assert_same_object(a: GraspObject, b: GraspObject) -> None:
    assert a.name == b.name and a.category == b.category and a.source == b.source
    assert a.mesh_hash == b.mesh_hash
    for x, y in ((a.vertices, b.vertices), (a.faces, b.faces)):
        assert x.dtype == y.dtype and x.tobytes() == y.tobytes()
    assert (a.face_parts is None) == (b.face_parts is None)
    if a.face_parts is not None:
        assert a.face_parts.dtype == b.face_parts.dtype
        assert a.face_parts.tobytes() == b.face_parts.tobytes()
    assert a.part_names == b.part_names and a.materials == b.materials
    for field in ("density", "volume", "mass", "r_max"):
        assert getattr(a.mass, field) == getattr(b.mass, field)
    for field in ("center_of_mass", "inertia", "bounds"):
        assert getattr(a.mass, field).tobytes() == getattr(b.mass, field).tobytes()


def assert_same_derived(a: prepared.DerivedGeometry, b: prepared.DerivedGeometry) -> None:
    for m, n in ((a.mesh, b.mesh), (a.centred, b.centred)):
        assert m.scale == n.scale
        for field in ("vertices", "faces", *prepared._MESH_FIELDS):
            x, y = getattr(m, field), getattr(n, field)
            assert (x is None) == (y is None), field
            if x is not None:
                assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), field
    assert a.origin.tobytes() == b.origin.tobytes()
    assert a.hull_vertices.tobytes() == b.hull_vertices.tobytes()
    assert a.samples.spacing == b.samples.spacing
    for field in prepared._SAMPLE_FIELDS:
        x, y = getattr(a.samples, field), getattr(b.samples, field)
        assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), field


@pytest.mark.parametrize(("family", "seed", "materials"), [("mug", 0, False), ("knife", 3, True)])
def test_a_cached_family_is_the_fresh_build_bit_for_bit(cache, family, seed, materials):
    fresh = resolve._build_family(family, seed, 1.0, materials, None, None)
    first = load_object(f"{family}:{seed}", materials=materials)  # builds and stores
    assert list(cache.glob("family-*.npz"))
    resolve._resolve_family.cache_clear()
    loaded = load_object(f"{family}:{seed}", materials=materials)  # from disk
    assert loaded is not first
    assert_same_object(loaded, fresh)
    assert_same_derived(prepared.derived_geometry(loaded), prepared._build_derived(fresh))
    # the mesh is built on demand, and is the same mesh
    mesh = loaded.mesh
    assert mesh.vertices.tobytes() == fresh.mesh.vertices.tobytes()
    assert np.array_equal(mesh.faces, fresh.mesh.faces)
    assert loaded.mesh is mesh


def test_derived_geometry_loaded_from_disk_is_the_fresh_one(cache):
    obj = load_object("hammer")
    built = prepared.derived_geometry(obj)  # computed and stored
    assert list(cache.glob("mesh-*.npz"))
    other = GraspObject(
        obj.name, obj.category, obj.mesh, obj.mass, obj.mesh_hash, obj.source, obj.face_parts
    )
    loaded = prepared.derived_geometry(other)  # another object, same mesh hash: from disk
    assert loaded is not built
    assert_same_derived(loaded, built)


def corrupt(path, how: str) -> None:
    data = bytearray(path.read_bytes())
    if how == "truncate":
        path.write_bytes(bytes(data[: len(data) // 2]))
    elif how == "flip":  # a byte inside the stored arrays: the zip still reads
        with np.load(path) as entry:
            arrays = {k: entry[k] for k in entry.files}
        arrays["vertices" if "vertices" in arrays else "hull_vertices"][0, 0] += 1e-3
        np.savez(path, **arrays)
    else:
        path.write_bytes(b"not an npz file")


@pytest.mark.parametrize("how", ["truncate", "flip", "garbage"])
def test_a_corrupt_entry_is_rebuilt_never_trusted(cache, how):
    reference = load_object("tumbler")
    derived = prepared.derived_geometry(reference)
    for path in sorted(cache.glob("*.npz")):
        corrupt(path, how)
    resolve._resolve_family.cache_clear()
    again = load_object("tumbler")
    assert again is not reference
    assert_same_object(again, reference)
    assert_same_derived(prepared.derived_geometry(again), derived)
    # and the entries were rewritten whole
    resolve._resolve_family.cache_clear()
    key = prepared.family_key("tumbler", 0, False, 1.0)
    assert prepared.load_family(key) is not None


def test_an_entry_of_other_code_or_libraries_is_not_used(cache, monkeypatch):
    load_object("tumbler")
    key = prepared.family_key("tumbler", 0, False, 1.0)
    assert prepared.load_family(key) is not None
    stale = dict(key, stamp="0" * 64)  # what another version would ask for
    assert prepared.load_family(stale) is None
    # the stamp follows the sources of the code that computes the entries
    monkeypatch.setattr(prepared, "_STAMPED_SOURCES", ("objects/prepared.py",))
    prepared.stamp.cache_clear()
    try:
        assert prepared.stamp() != key["stamp"]
    finally:
        prepared.stamp.cache_clear()


def test_a_family_entry_whose_mesh_does_not_hash_to_its_hash_is_refused(cache):
    load_object("tumbler")
    key = prepared.family_key("tumbler", 0, False, 1.0)
    obj = GraspObject(**prepared.load_family(key))
    forged = GraspObject(
        obj.name,
        obj.category,
        prepared.MeshData(obj.vertices + 1e-3, obj.faces, obj.mesh_hash),
        obj.mass,
        obj.mesh_hash,  # the hash of the other vertices
        obj.source,
        obj.face_parts,
        obj.part_names,
    )
    prepared.store_family(key, forged)
    assert prepared.load_family(key) is None


def fresh_file_object(path, **options) -> GraspObject:
    """A mesh file resolved without the cache, as before there was one."""
    density = options.pop("density", 1.0)
    mesh = load_mesh(path, **options)
    return resolve._build(path.name, "mesh", mesh, density, str(path.resolve()))


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".off", ".glb"])
def test_a_cached_mesh_file_is_the_fresh_build_bit_for_bit(cache, tmp_path, suffix):
    path = tmp_path / f"tool{suffix}"
    load_object("knife:3").mesh.export(path)
    fresh = fresh_file_object(path)
    first = load_object(path)  # reads, repairs and stores
    assert len(list(cache.glob("file-*.npz"))) == 1
    loaded = load_object(path)  # from disk
    assert loaded is not first and type(loaded.__dict__["_mesh"]) is prepared.MeshData
    assert_same_object(loaded, fresh)
    assert_same_derived(prepared.derived_geometry(loaded), prepared._build_derived(fresh))
    assert loaded.mesh.vertices.tobytes() == fresh.mesh.vertices.tobytes()


def test_a_mesh_file_entry_follows_the_files_bytes_and_the_options(cache, tmp_path):
    path = tmp_path / "block.stl"
    trimesh.creation.box((0.03, 0.05, 0.11)).export(path)
    first = load_object(path)
    assert load_object(path).mesh_hash == first.mesh_hash
    # the same name, other bytes: read again
    trimesh.creation.box((0.04, 0.05, 0.11)).export(path)
    edited = load_object(path)
    assert edited.mesh_hash != first.mesh_hash
    assert_same_object(edited, fresh_file_object(path))
    # other options: other entries, each what a fresh load gives
    for options in ({"size_m": 0.2}, {"units": "m", "density": 700.0}):
        assert_same_object(load_object(path, **options), fresh_file_object(path, **options))
        assert_same_object(load_object(path, **options), fresh_file_object(path, **options))
    assert len(list(cache.glob("file-*.npz"))) == 4
    # the same bytes at another path: the entry is shared, the name and source are the path's
    other = tmp_path / "copy" / "other.stl"
    other.parent.mkdir()
    other.write_bytes(path.read_bytes())
    copy = load_object(other)
    assert (copy.name, copy.source) == ("other.stl", str(other.resolve()))
    assert copy.mesh_hash == edited.mesh_hash


def test_a_mesh_file_edited_while_it_is_read_is_not_stored(cache, tmp_path, monkeypatch):
    path = tmp_path / "block.stl"
    trimesh.creation.box((0.03, 0.05, 0.11)).export(path)
    read = resolve.load_mesh

    def read_then_edit(*args, **kwargs):
        mesh = read(*args, **kwargs)
        trimesh.creation.box((0.04, 0.05, 0.11)).export(path)
        return mesh

    monkeypatch.setattr(resolve, "load_mesh", read_then_edit)
    load_object(path)
    assert not list(cache.glob("file-*.npz"))
    monkeypatch.undo()
    assert_same_object(load_object(path), fresh_file_object(path))


def test_a_mesh_files_material_library_is_part_of_its_key(cache, tmp_path):
    path = tmp_path / "block.obj"
    path.write_text(
        "mtllib block.mtl\n" + trimesh.creation.box((0.03, 0.05, 0.11)).export(file_type="obj")
    )
    (tmp_path / "block.mtl").write_text("newmtl a\nKd 1 0 0\n")
    key = prepared.mesh_file_key(path, size_m=None, units=None, density=1.0)
    assert key is not None and list(key["companions"]) == ["block.mtl"]
    (tmp_path / "block.mtl").write_text("newmtl a\nKd 0 1 0\n")
    assert prepared.mesh_file_key(path, size_m=None, units=None, density=1.0) != key
    assert_same_object(load_object(path), fresh_file_object(path))


def test_the_repair_warnings_of_a_mesh_file_are_logged_again_from_the_cache(
    cache, tmp_path, caplog
):
    box = trimesh.creation.box((0.03, 0.05, 0.11))
    path = tmp_path / "open.stl"
    trimesh.Trimesh(box.vertices, box.faces[1:], process=False).export(path)
    with caplog.at_level(logging.ERROR):  # not shown: recorded all the same
        load_object(path)
    assert not caplog.records
    with caplog.at_level(logging.WARNING, logger="affordgrasp"):
        loaded = load_object(path)
    messages = [(r.name, r.levelno, r.getMessage()) for r in caplog.records]
    assert messages == [
        (
            "affordgrasp.objects.loading",
            logging.WARNING,
            "open.stl was repaired: capped 1 hole (3 boundary edges, the widest 110 mm "
            "across) with flat faces",
        )
    ]
    assert_same_object(loaded, fresh_file_object(path))


@pytest.mark.parametrize("how", ["truncate", "flip", "garbage"])
def test_a_corrupt_mesh_file_entry_is_rebuilt_never_trusted(cache, tmp_path, how):
    path = tmp_path / "block.stl"
    trimesh.creation.box((0.03, 0.05, 0.11)).export(path)
    reference = load_object(path)
    (entry,) = cache.glob("file-*.npz")
    corrupt(entry, how)
    again = load_object(path)
    assert_same_object(again, reference)
    key = prepared.mesh_file_key(path, size_m=None, units=None, density=1.0)
    assert prepared.load_mesh_file(key, path.name, str(path)) is not None  # rewritten whole
    stale = dict(key, stamp="0" * 64)
    assert prepared.load_mesh_file(stale, path.name, str(path)) is None


def test_bad_options_for_a_mesh_file_fail_before_the_cache(cache, box_mesh):
    with pytest.raises(InputError, match="size_m"):
        load_object(box_mesh, size_m=-1.0)
    with pytest.raises(InputError, match="unit"):
        load_object(box_mesh, units="furlong")
    assert not list(cache.glob("file-*.npz"))


def test_family_names_are_the_builders_names():
    assert family_names.CATEGORIES == {n: f.category for n, f in families.FAMILIES.items()}
    assert list(family_names.CATEGORIES) == list(families.FAMILIES)
    assert family_names.ALIASES == families.ALIASES
