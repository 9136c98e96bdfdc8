"""A corpus of hostile inputs, generated here, each run through the command line.

Every case must end in one of two ways, and the corpus says which:

* ``ok``: exit 0 with a correct result (the object's volume as expected after repair, and
  the evaluation of every sample);
* ``refused``: exit 2 with a one-line message on stderr that names the problem.

Never exit 1 (an internal error) and never a traceback. The counts per category are printed
with ``pytest -s`` (and reported in the release notes).

``COMMAND_CASES`` (at the end) covers the other commands: outputs that cannot be written,
physics settings outside their physical ranges, unknown metrics in a tasks file, a sample
count whose table cannot fit, foreign and non-finite model files. Interrupts, orphaned
workers and large meshes have their own tests (``runtime/test_interrupts.py``,
``dataset/test_signals.py``, ``objects/test_simplify.py``, ``grasp/test_surface.py``).
"""

from __future__ import annotations

import json
import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import trimesh

from affordgrasp.cli import main

CUBE = 0.05  # m, a graspable block
CUBE_VOLUME = CUBE**3


@dataclass
class Case:
    name: str
    category: str
    expect: str  # "ok" or "refused"
    make: object  # (folder) -> path or spec string
    options: list[str] = field(default_factory=list)
    volume: float | None = None  # expected volume after repair (m^3), for "ok"
    refusal: str = ""  # a fragment the one-line message must contain
    evaluate: bool = True  # also simulate a few grasps (ok cases)


def _box(size=CUBE, offset=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    box = trimesh.creation.box((size, size, size))
    box.apply_translation(offset)
    return box


def _write(mesh: trimesh.Trimesh, name: str):
    def make(folder: Path) -> Path:
        path = folder / name
        mesh.export(path)
        return path

    return make


def _raw(name: str, data: bytes | str):
    def make(folder: Path) -> Path:
        path = folder / name
        path.write_bytes(data.encode() if isinstance(data, str) else data)
        return path

    return make


def _off(vertices, faces, header="OFF", comment="", colour="") -> str:
    lines = [header, f"{len(vertices)} {len(faces)} 0{comment}"]
    lines += [" ".join(repr(float(c)) for c in v) for v in vertices]
    lines += [f"{len(f)} " + " ".join(str(i) for i in f) + colour for f in faces]
    return "\n".join(lines) + "\n"


def _obj(vertices, faces) -> str:
    lines = ["v " + " ".join(repr(float(c)) for c in vertex) for vertex in vertices]
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in faces]
    return "\n".join(lines) + "\n"


def _mesh(vertices, faces) -> trimesh.Trimesh:
    return trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces), process=False)


def _cases() -> list[Case]:
    box = _box()
    v, f = box.vertices, box.faces
    quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    qv = np.array([[x, y, z] for x in (0, CUBE) for y in (0, CUBE) for z in (0, CUBE)])
    # The two triangles of one side of the box: a square hole when both are removed.
    side = np.flatnonzero(np.isclose(box.face_normals[:, 0], 1.0))
    holed = np.delete(f, side, axis=0)
    flipped_one = f.copy()
    flipped_one[0] = flipped_one[0][::-1]
    fin = _mesh(
        np.vstack([v, [[CUBE * 1.5, 0.0, CUBE / 2]]]),
        np.vstack([f, [[*_shared_edge(box), 8]]]),
    )
    soup = _mesh(v[f.reshape(-1)], np.arange(len(f) * 3).reshape(-1, 3))
    second = _box(offset=(CUBE / 2, 0, 0))
    far = _box(offset=(3 * CUBE, 0, 0))
    inner = _box(CUBE / 2)
    inner.invert()
    rng = np.random.default_rng(0)
    random_soup = _mesh(rng.normal(size=(60, 3)) * 0.05, np.arange(60).reshape(-1, 3))
    stl = _box().export(file_type="stl")
    ply = _box().export(file_type="ply")
    glb = _box().export(file_type="glb")
    nan_v = v.copy()
    nan_v[3, 1] = np.nan
    inf_v = v.copy()
    inf_v[5, 2] = np.inf

    ok_box = {"volume": CUBE_VOLUME}
    seam_v, seam_f = _seam_ball()
    ball = trimesh.Trimesh(seam_v, seam_f)
    ball.merge_vertices(digits_vertex=3)  # the seam welded: the sphere it stands for
    three = trimesh.Scene([_box(), _box(offset=(2 * CUBE, 0, 0)), _box(offset=(4 * CUBE, 0, 0))])
    return [
        # ------------------------------------------------------------ formats and files
        Case("cube.obj", "format", "ok", _write(box, "cube.obj"), **ok_box),
        Case("cube ascii.stl", "format", "ok", _write(box, "cube ascii.stl"), **ok_box),
        Case("cube binary.stl", "format", "ok", _raw("cube.stl", stl), **ok_box),
        Case("cube.ply", "format", "ok", _raw("cube.ply", ply), **ok_box),
        Case("cube.glb", "format", "ok", _raw("cube.glb", glb), **ok_box),
        Case("cube.off", "format", "ok", _raw("cube.off", _off(v, f)), **ok_box),
        Case("off quads", "format", "ok", _raw("q.off", _off(qv, quads)), **ok_box),
        Case("off lower-case header", "format", "ok", _raw("l.off", _off(qv, quads, "off"))),
        Case(
            "off comment after counts",
            "format",
            "ok",
            _raw("c.off", _off(qv, quads, comment=" # a comment")),
            **ok_box,
        ),
        Case("off colours", "format", "ok", _raw("k.off", _off(qv, quads, colour=" 255 0 0"))),
        Case("obj quads", "format", "ok", _raw("q.obj", _obj(qv, quads)), **ok_box),
        Case("unicode path", "format", "ok", _write(box, "tête_ü_🔧 клин.obj"), **ok_box),
        Case(
            "truncated off",
            "format",
            "refused",
            _raw("t.off", _off(v, f)[:120]),
            refusal="t.off",
        ),
        Case("truncated binary stl", "format", "refused", _raw("t.stl", stl[:300])),
        Case("truncated ply", "format", "refused", _raw("t.ply", ply[: len(ply) // 2])),
        Case("truncated glb", "format", "refused", _raw("t.glb", glb[: len(glb) // 2])),
        Case("garbage .obj", "format", "refused", _raw("g.obj", rng.bytes(4096))),
        Case("garbage .off", "format", "refused", _raw("g.off", rng.bytes(4096))),
        Case("garbage .glb", "format", "refused", _raw("g.glb", rng.bytes(4096))),
        Case("garbage .stl", "format", "refused", _raw("g.stl", b"\x00" * 80 + rng.bytes(500))),
        Case("empty .obj", "format", "refused", _raw("e.obj", b"")),
        Case("empty .stl", "format", "refused", _raw("e.stl", b"")),
        Case("empty .off", "format", "refused", _raw("e.off", b"")),
        Case("off header only", "format", "refused", _raw("h.off", "OFF\n0 0 0\n")),
        Case(
            "wrong extension .txt",
            "format",
            "refused",
            _raw("cube.txt", _obj(v, f)),
            refusal="unsupported",
        ),
        Case("no extension", "format", "refused", _raw("cube", _obj(v, f))),
        Case("obj text in a .stl", "format", "refused", _raw("obj.stl", _obj(v, f))),
        Case("directory named .obj", "format", "refused", _folder("d.obj"), refusal="not a file"),
        Case(
            "missing file",
            "format",
            "refused",
            lambda d: d / "missing.obj",
            refusal="unknown object",
        ),
        Case(
            "off index out of range",
            "format",
            "refused",
            _raw("i.off", _off(v, [*f[:-1], [0, 1, 99]])),
        ),
        Case(
            "off negative index", "format", "refused", _raw("n.off", _off(v, [*f[:-1], [0, -1, 2]]))
        ),
        Case(
            "obj index out of range",
            "format",
            "refused",
            _raw("i.obj", _obj(v, [*f[:-1], [0, 1, 99]])),
        ),
        Case("off NaN vertex", "format", "refused", _raw("nan.off", _off(nan_v, f)), refusal="NaN"),
        Case("obj NaN vertex", "format", "refused", _raw("nan.obj", _obj(nan_v, f))),
        Case("off inf vertex", "format", "refused", _raw("inf.off", _off(inf_v, f))),
        Case("ply NaN vertex", "format", "refused", _write(_mesh(nan_v, f), "nan.ply")),
        # -------------------------------------------------------- geometry and repair
        Case(
            "one flipped face",
            "geometry",
            "ok",
            _write(_mesh(v, flipped_one), "flip1.obj"),
            **ok_box,
        ),
        Case("inside out", "geometry", "ok", _write(_mesh(v, f[:, ::-1]), "inv.obj"), **ok_box),
        Case("one face missing", "geometry", "ok", _write(_mesh(v, f[1:]), "open1.obj"), **ok_box),
        Case("square hole", "geometry", "ok", _write(_mesh(v, holed), "open2.obj"), **ok_box),
        Case(
            "duplicated faces",
            "geometry",
            "ok",
            _write(_mesh(v, np.vstack([f, f[:4]])), "dup.obj"),
            **ok_box,
        ),
        Case(
            "zero-area faces",
            "geometry",
            "ok",
            _write(_mesh(v, np.vstack([f, [[0, 0, 1], [2, 2, 2]]])), "zero.obj"),
            **ok_box,
        ),
        Case("unmerged soup", "geometry", "ok", _write(soup, "soup.obj"), **ok_box),
        Case("non-manifold fin", "geometry", "ok", _write(fin, "fin.obj"), **ok_box),
        Case(
            "overlapping bodies",
            "geometry",
            "ok",
            _write(trimesh.util.concatenate([box, second]), "two.obj"),
            volume=1.5 * CUBE_VOLUME,
        ),
        Case(
            "disjoint bodies",
            "geometry",
            "ok",
            _write(trimesh.util.concatenate([box, far]), "apart.obj"),
            volume=2 * CUBE_VOLUME,
        ),
        Case(
            "cavity",
            "geometry",
            "ok",
            _write(trimesh.util.concatenate([box, inner]), "hollow.obj"),
            volume=CUBE_VOLUME * 7 / 8,
        ),
        Case(
            "sphere seam written twice, mm",
            "geometry",
            "ok",
            _raw("seam.off", _off(seam_v, seam_f)),
            ["--units", "mm"],
            volume=ball.volume * 1e-9,
        ),
        Case(
            "three separate bodies",
            "geometry",
            "ok",
            _raw("three.glb", three.export(file_type="glb")),
            volume=3 * CUBE_VOLUME,
        ),
        Case(
            "mesh file named like a scan variant",
            "format",
            "ok",
            _write(box, "knife~scan.stl"),
            **ok_box,
        ),
        Case(
            "sphere",
            "geometry",
            "ok",
            _write(trimesh.creation.icosphere(3, 0.04), "ball.stl"),
            volume=4 / 3 * np.pi * 0.04**3 * 0.99,
        ),
        Case(
            "thin blade",
            "geometry",
            "ok",
            _write(trimesh.creation.box((0.2, 0.03, 0.0005)), "blade.stl"),
            volume=0.2 * 0.03 * 0.0005,
        ),
        Case(
            "single triangle", "geometry", "refused", _write(_mesh(v[:3], [[0, 1, 2]]), "tri.obj")
        ),
        Case(
            "flat quad",
            "geometry",
            "refused",
            _write(_mesh(qv[:4], [[0, 1, 3], [0, 3, 2]]), "quad.obj"),
        ),
        Case(
            "collinear faces",
            "geometry",
            "refused",
            _raw("line.off", _off([[0, 0, 0], [0.01, 0, 0], [0.02, 0, 0]], [[0, 1, 2]])),
        ),
        Case(
            "one point",
            "geometry",
            "refused",
            _raw("pt.off", _off([[0.01, 0.01, 0.01]] * 3, [[0, 1, 2]])),
        ),
        Case("random triangle soup", "geometry", "refused", _write(random_soup, "rand.obj")),
        # ------------------------------------------------------------------- scale
        Case(
            "mm cube, no units",
            "scale",
            "refused",
            _write(_box(50.0), "mm.stl"),
            refusal="--units mm",
        ),
        Case(
            "mm cube --units mm",
            "scale",
            "ok",
            _write(_box(50.0), "mm.stl"),
            ["--units", "mm"],
            **ok_box,
        ),
        Case(
            "mm cube --size-m",
            "scale",
            "ok",
            _write(_box(50.0), "mm.stl"),
            ["--size-m", "0.05"],
            **ok_box,
        ),
        Case("km cube", "scale", "refused", _write(_box(1000.0), "km.stl"), refusal="m long"),
        Case("4.9 m cube", "scale", "refused", _write(_box(4.9), "big.stl"), refusal="--units"),
        Case("1 mm cube", "scale", "refused", _write(_box(0.001), "tiny.stl"), refusal="--size-m"),
        Case("1e300 coordinates", "scale", "refused", _raw("huge.obj", _obj(qv * 2e301, quads))),
        Case(
            "far from the origin",
            "scale",
            "ok",
            _write(_box(offset=(1e6, -2e6, 5e5)), "far.obj"),
            **ok_box,
        ),
        Case("cube --size-m 0", "scale", "refused", _write(box, "s0.obj"), ["--size-m", "0"]),
        Case("cube --size-m nan", "scale", "refused", _write(box, "snan.obj"), ["--size-m", "nan"]),
        Case("cube --size-m 10", "scale", "refused", _write(box, "s10.obj"), ["--size-m", "10"]),
        Case(
            "cube --units furlong", "scale", "refused", _write(box, "u.obj"), ["--units", "furlong"]
        ),
        Case(
            "both --units and --size-m",
            "scale",
            "refused",
            _write(box, "b.obj"),
            ["--units", "mm", "--size-m", "0.1"],
        ),
        # ------------------------------------------------------------------ arguments
        Case(
            "family typo",
            "arguments",
            "refused",
            lambda d: "hamer",
            refusal="did you mean 'hammer'",
        ),
        Case("bad family seed", "arguments", "refused", lambda d: "knife:abc", refusal="seed"),
        Case("scan variant, its own seed", "arguments", "ok", lambda d: "knife~scan:2"),
        Case("unknown task", "arguments", "refused", lambda d: "knife", ["--task", "hamering"]),
        Case("unknown mode", "arguments", "refused", lambda d: "knife", ["--mode", "strict"]),
        Case("unknown hand", "arguments", "refused", lambda d: "knife", ["--hand", "shadow"]),
        Case("zero samples", "arguments", "refused", lambda d: "knife", ["--samples", "0"]),
        Case("negative seed", "arguments", "refused", lambda d: "knife", ["--seed", "-1"]),
        Case("--out is a folder", "arguments", "refused", lambda d: "knife", ["--out", "."]),
    ]


def _seam_ball(radius=40.0, n_lat=12, n_lon=24) -> tuple[np.ndarray, np.ndarray]:
    """A UV sphere (mm) whose seam meridian is written twice, the copy 1e-5 mm away."""
    theta = np.pi * np.arange(1, n_lat) / n_lat
    phi = 2 * np.pi * (np.arange(n_lon + 1) % n_lon) / n_lon
    t, p = np.meshgrid(theta, phi, indexing="ij")
    rings = radius * np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1)
    rings[:, -1, 2] += 1e-5
    index = np.arange((n_lat - 1) * (n_lon + 1)).reshape(n_lat - 1, n_lon + 1)
    a, b, c, d = index[:-1, :-1], index[:-1, 1:], index[1:, :-1], index[1:, 1:]
    top, bottom = index.size, index.size + 1
    faces = [np.stack([a, c, b], -1), np.stack([b, c, d], -1)]
    faces += [np.stack([np.full(n_lon, top), index[0, :-1], index[0, 1:]], -1)]
    faces += [np.stack([np.full(n_lon, bottom), index[-1, 1:], index[-1, :-1]], -1)]
    vertices = np.vstack([rings.reshape(-1, 3), [[0, 0, radius], [0, 0, -radius]]])
    return vertices, np.vstack([f.reshape(-1, 3) for f in faces])


def _shared_edge(box: trimesh.Trimesh) -> list[int]:
    """Two vertices of an edge of the box on its x = max face (the fin hangs off it)."""
    right = np.flatnonzero(np.isclose(box.vertices[:, 0], box.vertices[:, 0].max()))
    edges = {tuple(sorted(e)) for e in box.edges_unique.tolist()}
    for a in right:
        for b in right:
            if a < b and (a, b) in edges:
                return [int(a), int(b)]
    raise AssertionError("no edge found")


def _folder(name: str):
    def make(folder: Path) -> Path:
        path = folder / name
        path.mkdir()
        return path

    return make


CASES = _cases()
OUTCOMES: Counter = Counter()
SAMPLES = 3


def _run(argv: list[str], capsys) -> tuple[int, str, str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(argv)
    captured = capsys.readouterr()
    # A warning would be one more line on the user's stderr.
    shown = [f"{w.category.__name__}: {w.message} ({w.filename}:{w.lineno})" for w in caught]
    assert not shown, "\n".join(shown)
    return code, captured.out, captured.err


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_hostile_input(case: Case, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    spec = str(case.make(tmp_path))
    if case.category == "arguments":
        argv = ["evaluate", spec, "--samples", str(SAMPLES), *case.options, "--json"]
        if "--samples" in case.options:
            argv = ["evaluate", spec, *case.options, "--json"]
    else:
        argv = ["objects", "export", spec, *case.options, "-o", str(tmp_path / "out.obj")]
        argv.append("--json")
    code, out, err = _run(argv, capsys)
    assert "Traceback" not in err, err
    assert code in (0, 2), f"exit {code} (internal error): {err}"
    outcome = "ok" if code == 0 else "refused"
    OUTCOMES[(case.category, outcome)] += 1
    assert outcome == case.expect, f"expected {case.expect}, got exit {code}: {err.strip()}"
    if outcome == "refused":
        lines = [line for line in err.splitlines() if line.strip()]
        assert len(lines) == 1, err
        assert lines[0].startswith(f"affordgrasp {argv[0]}: error: "), lines[0]
        assert case.refusal in lines[0], lines[0]
        return
    doc = json.loads(out)
    if case.volume is not None:
        assert doc["volume_m3"] == pytest.approx(case.volume, rel=0.02)
    if not case.evaluate or case.category == "arguments":
        return
    code, out, err = _run(
        ["evaluate", spec, "--samples", str(SAMPLES), *case.options, "--json"], capsys
    )
    assert code == 0, err
    result = json.loads(out)
    assert sum(s["count"] for s in result["status"].values()) == SAMPLES


def test_corpus_size_and_report():
    """Run last in this file: the corpus is large enough and every case was decided."""
    counts = Counter(c.category for c in CASES)
    assert len(CASES) >= 60, counts
    expected = Counter((c.category, c.expect) for c in CASES)
    if sum(OUTCOMES.values()) == len(CASES):  # the whole corpus ran in this session
        assert OUTCOMES == expected
        report = ", ".join(f"{cat} {n} {how}" for (cat, how), n in sorted(OUTCOMES.items()))
        print(f"\nhostile inputs: {len(CASES)} cases; {report}")


# ---------------------------------------------------------------------------- commands
# Beyond mesh files: outputs that cannot be written, settings outside physical ranges,
# task files naming unknown metrics, sample counts whose table cannot fit, foreign model
# files. Each is refused before any work, with exit 2 and one line naming the problem.


def _tasks_file(folder: Path) -> str:
    path = folder / "tasks.toml"
    path.write_text('[tasks.bogus]\nvalue = "epsilon * nosuchmetric"\n')
    return str(path)


def _foreign_model(folder: Path) -> str:
    pytest.importorskip("torch")
    from affordgrasp.learning.io import save_model
    from affordgrasp.learning.models import build_model
    from affordgrasp.learning.targets import make_target
    from affordgrasp.learning.training import default_config

    config = default_config("cnn", make_target("viable"), width=8)
    wide = build_model(default_config("cnn", make_target("viable"), width=16))
    path = folder / "foreign.safetensors"
    save_model(path, wide, config)  # weights of a wider network under this config
    return str(path)


def _nan_model(folder: Path) -> str:
    torch = pytest.importorskip("torch")
    from affordgrasp.learning.io import save_model
    from affordgrasp.learning.models import build_model
    from affordgrasp.learning.targets import make_target
    from affordgrasp.learning.training import default_config

    config = default_config("pose", make_target("viable"))
    model = build_model(config)
    with torch.no_grad():
        for p in model.parameters():
            p.fill_(float("nan"))
    path = folder / "nan.safetensors"
    save_model(path, model, config)
    return str(path)


COMMAND_CASES = [
    # (id, argv builder (folder) -> argv, fragment of the one-line message)
    (
        "depth -o under a missing folder",
        lambda d: ["depth", "knife", "--sample", "1", "-o", "missing/dir/d.png"],
        "does not exist",
    ),
    (
        "objects export -o in /proc",
        lambda d: ["objects", "export", "knife", "-o", "/proc/k.obj"],
        "takes no new files",
    ),
    (
        "objects export -o a folder",
        lambda d: ["objects", "export", "knife", "-o", "."],
        "is a directory",
    ),
    (
        "evaluate --out under a missing folder",
        lambda d: ["evaluate", "knife", "--samples", "2", "--out", "no/x.parquet"],
        "does not exist",
    ),
    (
        "simulate --out in /proc",
        lambda d: ["simulate", "knife", "--samples", "2", "--out", "/proc/x.parquet"],
        "takes no new files",
    ),
    (
        "generate --out a file",
        lambda d: ["generate", "knife", "--samples", "2", "--out", _tasks_file(d)],
        "is a file, not a directory",
    ),
    (
        "generate --out in /proc",
        lambda d: ["generate", "knife", "--samples", "2", "--out", "/proc/ds"],
        "takes no new files",
    ),
    (
        "show -o in /proc",
        lambda d: ["show", "knife", "--task", "cut", "-o", "/proc/show"],
        "takes no new files",
    ),
    ("plots -o in /proc", lambda d: ["plots", "knife", "-o", "/proc/plots"], "takes no new files"),
    (
        "best --out under a missing folder",
        lambda d: ["best", "nodata", "--task", "cut", "--out", "no/b.parquet"],
        "does not exist",
    ),
    (
        "train -o under a missing folder",
        lambda d: ["train", "nodata", "-o", "no/m.safetensors"],
        "does not exist",
    ),
    (
        "predict --out in /proc",
        lambda d: ["predict", "default", "nodata", "--out", "/proc/p.parquet"],
        "takes no new files",
    ),
    (
        "physics --out in /proc",
        lambda d: ["physics", "nodata", "--out", "/proc/ph"],
        "takes no new files",
    ),
    (
        "physics --timestep 10",
        lambda d: ["physics", "nodata", "--out", "ph", "--timestep", "10"],
        "timestep = 10.0 s is outside",
    ),
    (
        "physics --timestep too coarse",
        lambda d: ["physics", "nodata", "--out", "ph", "--timestep", "0.005"],
        "too coarse",
    ),
    (
        "physics --load-factor 1e6",
        lambda d: ["physics", "nodata", "--out", "ph", "--load-factor", "1e6"],
        "load_factor",
    ),
    (
        "physics --density 1e9",
        lambda d: ["physics", "nodata", "--out", "ph", "--density", "1e9"],
        "density",
    ),
    (
        "unknown metric in a tasks file",
        lambda d: ["evaluate", "knife", "--samples", "2", "--tasks-file", _tasks_file(d)],
        "unknown metric 'nosuchmetric'",
    ),
    (
        "evaluate --samples 1e9",
        lambda d: ["evaluate", "knife", "--samples", "1000000000"],
        "GB of rows in memory",
    ),
    (
        "predict with a foreign model",
        lambda d: ["predict", _foreign_model(d), "nodata", "--out", "p.parquet"],
        "but its config",
    ),
    (
        "predict with NaN weights",
        lambda d: ["predict", _nan_model(d), "nodata", "--out", "p.parquet"],
        "non-finite values",
    ),
    (
        "evaluate --tasks-file a folder",
        lambda d: ["evaluate", "knife", "--samples", "2", "--tasks-file", str(d)],
        "is a directory; give a .toml file",
    ),
    (
        "depth --size 100000",
        lambda d: ["depth", "knife", "--sample", "1", "--size", "100000", "-o", "d.png"],
        "at most 4096 pixels per side",
    ),
    (
        "optimize --population 0",
        lambda d: ["optimize", "knife", "--task", "pick", "--budget", "20", "--population", "0"],
        "must be an integer >= 2",
    ),
    (
        "optimize --population 1",
        lambda d: ["optimize", "knife", "--task", "pick", "--budget", "20", "--population", "1"],
        "must be an integer >= 2",
    ),
    (
        "show --mesh a text file",
        lambda d: ["show", "nodata", "--task", "pick", "--mesh", _tasks_file(d), "-o", "s"],
        "is not a mesh file",
    ),
    (
        "evaluate --out a .csv name",
        lambda d: ["evaluate", "knife", "--samples", "2", "--out", "rows.csv"],
        "must end in .parquet",
    ),
    (
        "model-eval --task unknown",
        lambda d: ["model-eval", "default", "nodata", "--task", "nosuch"],
        "unknown task 'nosuch'",
    ),
    (
        "plots --mesh a missing file",
        lambda d: ["plots", "nodata", "--mesh", "no.stl", "-o", "p"],
        "does not exist",
    ),
]


@pytest.mark.parametrize(
    "build, fragment", [c[1:] for c in COMMAND_CASES], ids=[c[0] for c in COMMAND_CASES]
)
def test_hostile_command(build, fragment, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = build(tmp_path)
    code, out, err = _run(argv, capsys)
    assert "Traceback" not in err and "internal error" not in err, err
    assert code == 2, f"exit {code}: {err}"
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith(f"affordgrasp {argv[0]}: error: "), lines[0]
    assert fragment in lines[0], lines[0]
    # Refused before any work: nothing was written where the command was run.
    assert {p.name for p in tmp_path.iterdir()} <= {
        "tasks.toml",
        "foreign.safetensors",
        "nan.safetensors",
    }


# ---------------------------------------------------------------------------- messages
# A run that finds nothing, or a refusal, says what to do with options the command has.


@pytest.fixture(scope="module")
def small_dataset(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("messages") / "ds"
    assert (
        main(["generate", "knife:1", "--samples", "12", "--out", str(out), "--workers", "1"]) == 0
    )
    return out


def test_nothing_found_suggests_only_what_would_change(small_dataset, capsys):
    never = ["--task", "cut-rules", "--threshold", "tau_eps=1e9"]  # no grasp passes
    for mode, suggested in (("default", True), ("no-robustness", False)):
        assert main(["best", str(small_dataset), *never, "--mode", mode]) == 0
        out = capsys.readouterr().out
        assert "no sample passes" in out and ("try --mode no-robustness" in out) == suggested
    show = ["show", str(small_dataset), *never, "--no-html", "-o", str(small_dataset.parent / "s")]
    assert main(show) == 0
    out = capsys.readouterr().out
    assert "a dataset with more samples" in out and "more --samples" not in out


def test_physics_says_how_to_restore_a_moved_mesh(tmp_path, capsys, monkeypatch):
    pytest.importorskip("mujoco")
    pytest.importorskip("coacd")
    monkeypatch.chdir(tmp_path)
    _box().export(tmp_path / "block.stl")
    assert main(["generate", "block.stl", "--samples", "4", "--out", "ds", "--workers", "1"]) == 0
    (tmp_path / "block.stl").rename(tmp_path / "moved.stl")
    capsys.readouterr()
    code, _, err = _run(["physics", "ds", "--out", "ph", "--workers", "1"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "copy it into the dataset directory" in err and "--mesh" not in err
    assert not (tmp_path / "ph").exists()
