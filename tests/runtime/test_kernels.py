"""Kernels ready up front, caches valid after an install (kernels.py, runtime/kernel_cache.py)."""

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from affordgrasp import kernels as compiled
from affordgrasp.grasp import kernels
from affordgrasp.runtime import kernel_cache
from affordgrasp.vision import render_depth


def test_warm_up_runs_every_pipeline_kernel_and_reports_what_it_cost():
    compiled.warm_up()
    again = compiled.warm_up()  # everything is in memory now: nothing compiles
    assert not again.compiled
    assert again.seconds < 30
    assert "loaded from cache" in again.describe()
    for dispatcher in compiled._dispatchers():
        assert dispatcher.signatures, dispatcher.py_func.__name__


def test_warm_up_with_vision_also_makes_the_rasteriser_ready():
    compiled.warm_up(vision=True)
    again = compiled.warm_up(vision=True)
    assert not again.compiled
    for dispatcher in compiled._vision_dispatchers():
        assert dispatcher.signatures, dispatcher.py_func.__name__
    # the signature warmed up is the one a depth render calls: rendering compiles nothing
    dispatchers = compiled._vision_dispatchers()
    misses = [sum(d.stats.cache_misses.values()) for d in dispatchers]
    signatures = [list(d.signatures) for d in dispatchers]
    p0 = [[0.3, 0.1, -0.4, 0.2, -0.5, 0.7], [-0.6, 0.5, 0.2, 0.1, 0.3, 0.2]]
    depth = render_depth("knife", p0)
    # and the fusion of views (plan --model views) calls the carving kernel warmed up
    from affordgrasp.objects import load_object
    from affordgrasp.vision.depth import renderer_for
    from affordgrasp.vision.fusion import free_space_field

    renderer = renderer_for(load_object("knife"))
    free_space_field(depth, renderer.poses(p0), renderer.camera)
    assert [sum(d.stats.cache_misses.values()) for d in dispatchers] == misses
    assert [list(d.signatures) for d in dispatchers] == signatures


def test_building_the_package_warms_the_vision_kernels_up(monkeypatch):
    calls = []
    monkeypatch.setattr(compiled, "warm_up", lambda **kw: calls.append(kw) or LOADED)
    compiled.main()
    assert calls == [{"vision": True, "reference": True}]


def test_warm_up_also_readies_the_reference_paths_and_counts_every_compilation():
    compiled.warm_up(reference=True)
    assert not compiled.warm_up(reference=True).compiled
    # a compilation anywhere in the warm-up counts, not only in the listed dispatchers
    import numba

    with compiled._Compilations() as seen:
        numba.njit(lambda x: x * 3)(2)
    assert seen.count >= 1


LOADED = compiled.KernelLoad(0.5, False)


def test_cache_stamp_depends_on_contents_not_modification_times(tmp_path):
    # An install copies the sources with new modification times; caches built with the
    # wheel must stay valid, and an edited kernel must invalidate them.
    a = tmp_path / "a" / "grasp"
    a.mkdir(parents=True)
    shutil.copy(kernels.__file__, a / "kernels.py")
    stamp = kernel_cache.package_stamp.__wrapped__(tmp_path / "a")
    os.utime(a / "kernels.py", (1, 1))
    assert kernel_cache.package_stamp.__wrapped__(tmp_path / "a") == stamp
    (a / "kernels.py").write_text((a / "kernels.py").read_text() + "\n# edited\n")
    assert kernel_cache.package_stamp.__wrapped__(tmp_path / "a") != stamp


def test_every_kernel_of_the_package_uses_the_content_stamp():
    (locator_class,) = kernel_cache._installed
    func = kernels.first_contact.py_func
    locator = locator_class.from_function(func, func.__code__.co_filename)
    assert locator is not None
    assert locator.get_source_stamp() == ("affordgrasp-kernels", kernel_cache.package_stamp())


def test_the_object_files_symbol_table_names_what_the_kernels_bitcode_defines():
    # The light loading takes a cached kernel's defined symbols from its machine code's
    # symbol table instead of parsing its LLVM bitcode: cross-checked against the bitcode
    # (LLVM's own parser) on every kernel of the pipeline. Only private constants
    # (".const.", ".bytes." names, never looked up) are in the bitcode alone.
    import llvmlite.binding as ll

    compiled.warm_up()
    checked = 0
    for dispatcher in compiled._dispatchers():
        for signature, overload in dispatcher.overloads.items():
            cache = dispatcher._cache  # the kernel as numba stored it: (name, kind, data)
            key = cache._index_key(signature, overload.target_context.codegen())
            stored = cache._cache_file.load(key)
            if stored is None:
                pytest.skip("the kernel cache could not be written: nothing loads from it")
            _, kind, (object_code, bitcode) = stored[0]
            assert kind == "object"
            names = kernel_cache.elf_exported_symbols(object_code)
            if names is None:
                pytest.skip("this platform's object files are not ELF")
            module = ll.parse_bitcode(bitcode)
            defined = {
                value.name
                for values in (module.functions, module.global_variables)
                for value in values
                if not value.is_declaration
            }
            assert names <= defined, dispatcher.py_func.__name__
            private = defined - names  # private constants only
            assert all(name.startswith((".const.", ".bytes.")) for name in private), private
            assert overload.fndesc.llvm_cpython_wrapper_name in names
            checked += 1
    assert checked >= len(compiled._dispatchers())


def _elf_without_sections() -> bytes:
    """A valid 64-bit little-endian ELF header with no section table (nothing to name)."""
    import struct

    header = bytearray(64)
    header[:7] = b"\x7fELF\x02\x01\x01"
    struct.pack_into("<HHIQQQIHHHHHH", header, 16, 1, 62, 1, 0, 0, 0, 0, 64, 0, 0, 64, 0, 0)
    return bytes(header)


@pytest.mark.parametrize(
    "data",
    [
        b"",
        b"not an object file",
        b"\x7fELF\x01\x01" + bytes(58),  # 32-bit
        b"\x7fELF\x02\x01" + bytes(10),  # truncated
        _elf_without_sections(),  # stripped: no symbol table
    ],
)
def test_a_non_elf_truncated_or_stripped_object_file_is_left_to_numba(data):
    # None sends the kernel to numba's own loading; an empty set would load it with no
    # entry point and crash on the first call
    assert kernel_cache.elf_exported_symbols(data) is None


def test_a_compilation_of_the_package_says_so_once_on_stderr(monkeypatch, capsys):
    import numba

    monkeypatch.setattr(kernel_cache._CompileNotice, "shown", False)

    def package_function(x):
        return x + 1

    def other_function(x):
        return x + 2

    package_function.__module__ = "affordgrasp.metrics.example"
    numba.njit(other_function)(1)  # not the package's: no notice
    assert capsys.readouterr().err == ""
    assert numba.njit(package_function)(1) == 2
    numba.njit(package_function)(2.5)  # a second compilation: still the one line
    err = capsys.readouterr().err
    assert err.count("compiling the numba kernels") == 1 and err.count("\n") == 1, err


def _installed_package() -> Path | None:
    """The package under test when it is an installed (non-editable) copy, else None."""
    import affordgrasp

    package = Path(affordgrasp.__file__).resolve().parent
    installed = any(part in ("site-packages", "dist-packages") for part in package.parts)
    return package if installed else None


@pytest.mark.skipif(
    _installed_package() is None,
    reason="the package under test is a source tree or an editable install (its kernels "
    "compile on first use); CI's non-editable install runs this",
)
def test_an_installed_package_loads_its_kernels_without_compiling(tmp_path):
    # The wheel ships numba's caches; an install copies the files with new modification
    # times. A copy with fresh times, in a new place, must still load every kernel.
    package = _installed_package()
    copy = tmp_path / "site" / package.name
    shutil.copytree(package, copy, copy_function=shutil.copyfile)  # no times kept
    later = time.time() + 3600
    for path in copy.rglob("*"):
        os.utime(path, (later, later))
    assert list(copy.rglob("*.nbi")), "the installed package holds no kernel caches"
    code = (
        "import json, affordgrasp\n"
        "from affordgrasp.kernels import warm_up\n"
        "load = warm_up(vision=True, reference=True)\n"
        "print(json.dumps({'compiled': load.compiled, 'file': affordgrasp.__file__}))"
    )
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env["PYTHONPATH"] = str(copy.parent)
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=tmp_path
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert Path(result["file"]).resolve().is_relative_to(copy.resolve())
    assert result["compiled"] is False, proc.stderr[-2000:]
    assert "compiling" not in proc.stderr
