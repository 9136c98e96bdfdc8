"""The public API is documented in numpydoc: sections that say what goes in and comes out."""

import inspect

import pytest

import affordgrasp as ag


@pytest.mark.parametrize("name", ag.__all__)
def test_front_door_names_have_numpydoc_sections(name):
    obj = getattr(ag, name)
    doc = inspect.getdoc(obj) or ""
    assert doc.strip(), f"ag.{name} has no docstring"
    if inspect.isclass(obj):
        assert "Attributes\n----------" in doc or "Parameters\n----------" in doc, name
        return
    params = [p for p in inspect.signature(obj).parameters.values() if p.name != "self"]
    if params:
        assert "Parameters\n----------" in doc, f"ag.{name} documents no Parameters section"
