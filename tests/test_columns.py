"""The metric column lists have one owner, affordgrasp/columns.py: no module defines them again."""

import ast
from pathlib import Path

import affordgrasp
from affordgrasp import columns

SRC = Path(affordgrasp.__file__).resolve().parent
OWNED = {
    "HOLD_EFFORT_SUFFIXES",
    "HOLD_EFFORT_COLUMNS",
    "HOLD_EFFORT_SUM",
    "USE_METRICS",
    "GRASP_METRICS",
    "METRIC_COLUMNS",
    "DERIVED_COLUMNS",
    "METRIC_UNITS",
}


def assigned_names(tree: ast.Module) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(tree):
        targets = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign)):
            targets = [node.target]
        names |= {t.id for t in targets if isinstance(t, ast.Name)}
        if isinstance(node, ast.FunctionDef) and node.name == "hold_effort_sum":
            names.add("hold_effort_sum()")
    return names


def test_the_owner_defines_every_owned_name():
    assert OWNED <= set(vars(columns))
    assert "hold_effort_sum()" in assigned_names(ast.parse((SRC / "columns.py").read_text()))


def test_no_other_module_defines_a_column_list_again():
    redefined = []
    for path in sorted(SRC.rglob("*.py")):
        if path == SRC / "columns.py":
            continue
        names = assigned_names(ast.parse(path.read_text(encoding="utf-8")))
        redefined += [
            f"{path.relative_to(SRC)}: {n}" for n in sorted(names & (OWNED | {"hold_effort_sum()"}))
        ]
    assert not redefined, "import these from affordgrasp.columns instead: " + ", ".join(redefined)


def test_the_physics_outcomes_report_the_numeric_metrics_and_the_contact_count():
    from affordgrasp.physics.run import REPORTED_METRICS

    assert set(REPORTED_METRICS) == (set(columns.METRIC_COLUMNS) - {"epsilon_reason"}) | {
        "n_contacts"
    }


def spelled_out_columns(tree: ast.Module) -> set[str]:
    """Column names of the owned lists written out as string literals, and sums over them."""
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and node.value in set(columns.HOLD_EFFORT_COLUMNS):
            found.add(node.value)
        if isinstance(node, ast.Call) and ast.unparse(node.func).split(".")[-1] == "sum":
            if "HOLD_EFFORT_COLUMNS" in ast.unparse(node):
                found.add("a sum over HOLD_EFFORT_COLUMNS (use hold_effort_sum)")
    return found


def test_no_module_spells_out_the_hold_efforts_or_sums_them_itself():
    found = []
    for path in sorted(SRC.rglob("*.py")):
        if path == SRC / "columns.py":
            continue
        names = spelled_out_columns(ast.parse(path.read_text(encoding="utf-8")))
        found += [f"{path.relative_to(SRC)}: {n}" for n in sorted(names)]
    assert not found, "use affordgrasp.columns instead: " + "; ".join(found)


def test_the_spelled_out_check_catches_both_habits():
    tree = ast.parse(
        "A = ('hold_effort_px', 'x')\nB = sum(col(c) for c in HOLD_EFFORT_COLUMNS)\nC = 'px'\n"
    )
    assert spelled_out_columns(tree) == {
        "hold_effort_px",
        "a sum over HOLD_EFFORT_COLUMNS (use hold_effort_sum)",
    }
