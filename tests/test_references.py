"""The repository documents itself: no reference to a SPEC document it does not contain, and
every repository path it names exists."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCANNED = ["src", "docs", "examples", "benchmarks", "studies", "tools", "README.md"]
WORD = re.compile(r"\bSPEC\b")  # case-sensitive: "spec" (an object spec) is a word of the API


def is_build_output(path: Path) -> bool:
    """Files the build or the interpreter writes (a stale egg-info copies an old README)."""
    return any(
        part == "__pycache__" or part.endswith(".egg-info") or part == "build"
        for part in path.relative_to(ROOT).parts
    )


def scanned_files() -> list[Path]:
    files: list[Path] = []
    for name in SCANNED:
        path = ROOT / name
        found = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
        files.extend(p for p in found if not is_build_output(p))
    return files


def test_the_scan_reads_the_repository():
    texts = [p for p in scanned_files() if p.suffix in {".py", ".md"}]
    assert len(texts) >= 50, "the scanned folders are missing: run the tests from a checkout"
    assert ROOT / "src" / "affordgrasp" / "metrics" / "epsilon.py" in texts


@pytest.mark.parametrize("name", SCANNED)
def test_no_reference_to_an_outside_spec(name):
    hits = []
    for path in scanned_files():
        if not path.is_relative_to(ROOT / name):
            continue
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue  # images and other binary files
        for number, line in enumerate(text.splitlines(), 1):
            if WORD.search(line):
                hits.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()[:80]}")
    assert not hits, "say it in docs/conventions.md instead:\n" + "\n".join(hits)


def test_build_outputs_are_not_scanned():
    assert is_build_output(ROOT / "src" / "affordgrasp.egg-info" / "PKG-INFO")
    assert is_build_output(ROOT / "src" / "affordgrasp" / "__pycache__" / "x.pyc")
    assert not is_build_output(ROOT / "src" / "affordgrasp" / "metrics" / "epsilon.py")


def test_the_pattern_catches_a_reference_and_spares_the_word_spec():
    assert WORD.search('"""Linear programs (SPEC §2.4)."""')
    assert WORD.search("the SPEC's normalised ε")
    assert not WORD.search("an object spec, a Spec grammar, USE_SPECULAR")


# A path into the repository's own folders, as prose and comments name it ("see
# studies/validate_scan.py"); CHANGELOG.md is not scanned: it names files as they were.
PATH = re.compile(r"(?<![\w/.-])((?:benchmarks|studies|tools|docs|examples|tests|src)/[\w./-]*\w)")


def test_every_named_repository_path_exists():
    missing = []
    for path in scanned_files():
        if path.suffix not in {".py", ".md", ".toml"}:
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for match in PATH.finditer(line):
                if not (ROOT / match.group(1)).exists():
                    missing.append(f"{path.relative_to(ROOT)}:{number}: {match.group(1)}")
    assert not missing, "named but not in the repository:\n" + "\n".join(missing)


def test_the_path_pattern_finds_repository_paths_only():
    found = PATH.findall(
        "see studies/validate_scan.py, `tools/x.py`; src/affordgrasp/ and a/docs/y"
    )
    assert found == ["studies/validate_scan.py", "tools/x.py", "src/affordgrasp"]
