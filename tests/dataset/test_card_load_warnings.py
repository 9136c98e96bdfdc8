"""The dataset card lists what loading each mesh file warned about (repairs, simplification)."""

from __future__ import annotations

import numpy as np
import trimesh

from affordgrasp.dataset.card import read_card
from affordgrasp.dataset.generate import generate
from affordgrasp.objects import load_object


def _holed_box(folder):
    box = trimesh.creation.box((0.05, 0.05, 0.05))
    side = np.flatnonzero(np.isclose(box.face_normals[:, 0], 1.0))
    holed = trimesh.Trimesh(box.vertices, np.delete(box.faces, side, axis=0), process=False)
    path = folder / "holed.obj"
    holed.export(path)
    return path


def test_card_lists_the_repairs_of_a_mesh_file(tmp_path, monkeypatch):
    monkeypatch.setenv("AFFORDGRASP_CACHE_DIR", str(tmp_path / "cache"))
    path = _holed_box(tmp_path)
    first = load_object(str(path))
    assert any("was repaired" in w for w in first.load_warnings), first.load_warnings
    again = load_object(str(path))  # from the cache: the same warnings
    assert again.load_warnings == first.load_warnings
    assert load_object("knife").load_warnings == ()

    out = tmp_path / "ds"
    generate(["knife", str(path)], 4, out, seed=0, workers=1, shard_size=4)
    card = read_card(out)
    by_name = {o["name"]: o for o in card["objects"]}
    assert by_name["holed.obj"]["load_warnings"] == list(first.load_warnings)
    assert by_name["knife:0"]["load_warnings"] == []
    markdown = (out / "_card.md").read_text()
    assert "Loading the mesh files:" in markdown and "holed.obj: " in markdown
