"""Keep numba's on-disk caches of the package's kernels valid, and shippable in a wheel.

numba (``cache=True``) stamps a cached function with the modification time and size of the
one file that defines it. Two problems follow:

* the metric kernels call kernels of sibling modules (ε calls the hull and the LP solver,
  Φ calls all of them) and inline them: after an edit of ``hull.py`` a cached
  ``epsilon_kernel`` would silently keep running the old hull;
* an install copies the sources with new modification times, so caches compiled when the
  package is built (see ``setup.py`` and :mod:`affordgrasp.kernels`) would all be stale.

The fix is a cache *locator* (numba's hook that says where a function's cache lives and
which stamp validates it): for functions defined anywhere in this package it keeps numba's
own location and replaces numba's stamp by a hash of the *contents* of every module of the
package that defines kernels. When any of them changes, no index matches and numba
recompiles and overwrites it; when nothing changed, caches built with the wheel load as
they are. Nothing is deleted. The locator is installed by every kernel module just before
its functions are decorated (:func:`install_package_stamp`, idempotent).
"""

from __future__ import annotations

import hashlib
import re
import struct
import sys
import weakref
from contextlib import contextmanager
from functools import cache, partial
from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parents[1]  # affordgrasp/
_DECORATED = re.compile(rb"^[ \t]*@njit", re.MULTILINE)  # a kernel's decorator line


@cache
def package_stamp(directory: Path = _PACKAGE_DIR) -> str:
    """Hash of the contents of every module under ``directory`` that defines compiled kernels.

    Computed once per process (a source edited while the process runs is seen by the next
    process, as for numba's own stamps).

    Parameters
    ----------
    directory : pathlib.Path
        Searched recursively; the package's directory by default.

    Returns
    -------
    str
        Hex digest.
    """
    digest = hashlib.sha256()
    for path in sorted(directory.rglob("*.py")):
        text = path.read_bytes()
        if b"@njit" in text and _DECORATED.search(text):  # the cheap test first
            digest.update(path.relative_to(directory).as_posix().encode())
            digest.update(hashlib.sha256(text).digest())
    return digest.hexdigest()


def _cache_impl():
    from numba.core import caching

    # the class that picks a locator: CacheImpl in recent numba, _CacheImpl before
    return getattr(caching, "CacheImpl", None) or caching._CacheImpl


def _make_locator_class():
    from numba.core import caching

    class PackageStampLocator(caching._CacheLocator):
        """numba's own locator for a function of this package, with the package stamp."""

        def __init__(self, inner):
            self._inner = inner

        def ensure_cache_path(self):
            self._inner.ensure_cache_path()

        def get_cache_path(self):
            return self._inner.get_cache_path()

        def get_source_stamp(self):
            # contents, not modification times: valid after an install copies the files
            return ("affordgrasp-kernels", package_stamp())

        def get_disambiguator(self):
            return self._inner.get_disambiguator()

        @classmethod
        def from_function(cls, py_func, py_file):
            try:
                inside = _PACKAGE_DIR in Path(py_file).resolve().parents
            except OSError:
                return None
            if not inside:
                return None
            for other in _cache_impl()._locator_classes:
                if other is cls:
                    continue
                inner = other.from_function(py_func, py_file)
                if inner is not None:
                    return cls(inner)
            return None

    return PackageStampLocator


# numba internals the light loading relies on: (object, attribute), checked at install time
def _light_loading_needs() -> list[tuple[object, str]]:
    from numba.core import caching, codegen
    from numba.core.runtime import rtsys

    return [
        (caching.Cache, "load_overload"),
        (caching.Cache, "_load_overload"),
        (caching.Cache, "_guard_against_spurious_io_errors"),
        (rtsys, "initialize"),
        (codegen.CPUCodegen, "unserialize_library"),
        (codegen.CPUCodeLibrary, "enable_object_caching"),
        (codegen.CPUCodeLibrary, "_set_compiled_object"),
        (codegen.CPUCodeLibrary, "_finalize_final_module"),
        (codegen.CPUCodeLibrary, "_get_module_for_linking"),
    ]


class _LightLoading:
    """Whether the light loading is in use in this process (off after its first failure)."""

    enabled = True
    failure: str | None = None
    loads = 0  # kernels loaded by the light path (read by the tests)


def _install_light_loading(locator: type) -> bool:
    """Load this package's cached kernels without refreshing numba's compiler registries.

    numba's ``Cache.load_overload`` first calls ``target_context.refresh()``, which imports
    and installs every typing and lowering registry of numba (about 0.2 s, most of a warm
    start-up's kernel loading). Loading machine code needs none of it: only numba's runtime
    (NRT: the kernels allocate arrays) and the symbols the generated code links against,
    which numba's context installs when it is created, except the hash secrets (installed
    here by importing ``numba.cpython.hashing``). The machine code itself loads without its
    LLVM bitcode (:func:`_unserialize_library`). A cache miss compiles, and numba's
    compiler refreshes the registries itself. Functions from anywhere else load as numba
    loads them.

    Parameters
    ----------
    locator : type
        The package's locator class: only functions it locates load the light way.

    Returns
    -------
    bool
        True when installed. This relies on internals of numba (``Cache.load_overload``,
        ``Cache._load_overload``, ``Cache._guard_against_spurious_io_errors``,
        ``rtsys.initialize``, and the code library's object-cache methods used by
        :func:`_unserialize_library`): when one of them is missing (another numba version)
        numba is left alone and loads the kernels its own way (a few tenths of a second
        slower).

    Notes
    -----
    When the light loading raises (any ``Exception``), that load is done again by numba's
    own ``load_overload`` and every later load of the process goes to numba directly: a
    change inside numba costs those tenths of a second, never a failed start-up.
    """
    if not all(hasattr(owner, name) for owner, name in _light_loading_needs()):
        return False
    from numba.core import caching
    from numba.core.runtime import rtsys

    original = caching.Cache.load_overload

    def load_overload(self, sig, target_context):
        light = _LightLoading.enabled and isinstance(
            getattr(getattr(self, "_impl", None), "locator", None), locator
        )
        if not light:
            return original(self, sig, target_context)
        try:
            import numba.cpython.hashing  # noqa: F401 - installs the hash-secret symbols

            _preload_lapack_tables()
            rtsys.initialize(target_context)
            codegen = target_context.codegen()
            with _unserialize_hook(codegen, partial(_unserialize_library, codegen)):
                with self._guard_against_spurious_io_errors():
                    data = self._load_overload(sig, target_context)
        except Exception as error:  # noqa: BLE001 - numba's own loading takes over
            _LightLoading.enabled = False
            _LightLoading.failure = f"{type(error).__name__}: {error}"
            # numba's own, even inside another load that installed the hook
            with _unserialize_hook(target_context.codegen(), None):
                return original(self, sig, target_context)
        if data is not None:
            _LightLoading.loads += 1
        return data

    load_overload.__wrapped__ = original  # type: ignore[attr-defined]
    caching.Cache.load_overload = load_overload
    return True


@contextmanager
def _unserialize_hook(codegen, hook):
    """Within the block, ``codegen.unserialize_library`` is ``hook`` (None: the class's own
    method); then whatever it was before (numba holds its compiler lock around a load, and
    a nested load restores what it found)."""
    previous = codegen.__dict__.get("unserialize_library")
    if hook is None:
        codegen.__dict__.pop("unserialize_library", None)
    else:
        codegen.unserialize_library = hook
    try:
        yield
    finally:
        if previous is None:
            codegen.__dict__.pop("unserialize_library", None)
        else:
            codegen.unserialize_library = previous


_ELF64_LITTLE = b"\x7fELF\x02\x01"
_SHT_SYMTAB = 2
_STB_GLOBAL, _STB_WEAK = 1, 2
_WRAPPER_PREFIX = "_ZN7cpython"  # numba's CPython wrappers: the cpython:: namespace, mangled


def elf_exported_symbols(object_code: bytes) -> set[str] | None:
    """Names an ELF object file defines for other code: global and weak symbols, not undefined.

    Reads the symbol tables of a 64-bit little-endian ELF file with :mod:`struct` (a few
    hundred symbols: under a millisecond).

    Parameters
    ----------
    object_code : bytes
        The object file, as numba caches a kernel's machine code.

    Returns
    -------
    set of str or None
        The names; None when the bytes are not a 64-bit little-endian ELF file (macOS and
        Windows write other formats), are malformed, or name nothing (no symbol table, as
        in a stripped file).
    """
    if object_code[:6] != _ELF64_LITTLE:
        return None
    try:
        (section_offset,) = struct.unpack_from("<Q", object_code, 0x28)
        entry_size, count = struct.unpack_from("<HH", object_code, 0x3A)
        # (name, type, flags, address, offset, size, link, info, alignment, entry size)
        sections = [
            struct.unpack_from("<IIQQQQIIQQ", object_code, section_offset + i * entry_size)
            for i in range(count)
        ]
        names: set[str] = set()
        for section in sections:
            if section[1] != _SHT_SYMTAB:
                continue
            start, size, strings = section[4], section[5], sections[section[6]][4]
            table = object_code[start : start + size]
            for name, info, _, index, _, _ in struct.iter_unpack("<IBBHQQ", table):
                if name and index != 0 and info >> 4 in (_STB_GLOBAL, _STB_WEAK):
                    end = object_code.index(b"\0", strings + name)
                    names.add(object_code[strings + name : end].decode())
        return names or None
    except (struct.error, IndexError, ValueError, UnicodeDecodeError):
        return None


def _unserialize_library(codegen, state):
    """numba's ``unserialize_library`` for a cached kernel, without parsing its LLVM bitcode.

    numba caches a kernel as its machine code (an object file) and the LLVM bitcode of the
    same functions, which only serves to inline them into a function compiled later. Its
    loading parses that bitcode and walks every function and global of it to learn which
    symbols the machine code defines: about 0.11 s for each of the two largest kernels, a
    quarter of a warm start-up's kernel loading. Here the defined symbols come from the
    object file's symbol table instead (the same names: what the bitcode adds are private
    constants, which nothing looks up by name), and the bitcode is parsed only when another
    function is compiled against this one. Anything else (numba's bitcode-only caches, a
    non-ELF platform) is left to numba.
    """
    name, kind, data = state
    symbols = elf_exported_symbols(data[0]) if kind == "object" else None
    # a kernel is entered through its CPython wrapper (numba's mangled "cpython" namespace):
    # without one, numba's way
    if symbols is None or not any(symbol.startswith(_WRAPPER_PREFIX) for symbol in symbols):
        return type(codegen).unserialize_library(codegen, state)
    object_code, shared_bitcode = data
    defined = codegen._engine._defined_symbols  # before any state changes: a failure here
    defined |= symbols  # falls back to numba's loading with nothing added to the engine
    library = codegen.create_library(name)
    library.enable_object_caching()
    library._set_compiled_object(object_code)
    library._finalize_final_module()
    library._get_module_for_linking = partial(
        _module_for_linking, weakref.proxy(library), shared_bitcode
    )
    return library


def _module_for_linking(library, shared_bitcode: bytes):
    """The library's LLVM module for linking into another, parsed on first use."""
    import llvmlite.binding as ll

    if library._shared_module is None:
        library._shared_module = ll.parse_bitcode(shared_bitcode)
    return library._shared_module


_LAPACK_TABLES = ("cython_blas", "cython_lapack")


def _preload_lapack_tables() -> None:
    """Load scipy's tables of BLAS/LAPACK function pointers without the rest of scipy.linalg.

    A kernel calling ``np.linalg`` asks numba's runtime for a LAPACK function on its first
    call, and numba imports ``scipy.linalg.cython_lapack`` (or ``cython_blas``) for its
    table of function pointers. Importing that module runs ``scipy.linalg/__init__`` first
    (with ``scipy._lib``, array-API shims, ``numpy.testing``...: about 0.15 s of CPU), of
    which only the extension module is needed. Loading the extension module alone (a few
    ms) under its full name makes numba's import find it; a later ``import scipy.linalg``
    still runs the package and uses this same module. Any failure leaves it to numba.
    """
    if "scipy.linalg" in sys.modules:
        return
    try:
        import importlib.machinery
        import importlib.util

        scipy = sys.modules.get("scipy")
        if scipy is None:
            return
        directory = Path(next(iter(scipy.__path__))) / "linalg"
        for name in _LAPACK_TABLES:
            full = f"scipy.linalg.{name}"
            if full in sys.modules:
                continue
            for suffix in importlib.machinery.EXTENSION_SUFFIXES:
                path = directory / f"{name}{suffix}"
                if path.is_file():
                    spec = importlib.util.spec_from_file_location(full, path)
                    if spec is None or spec.loader is None:
                        break
                    module = importlib.util.module_from_spec(spec)
                    spec.loader.exec_module(module)
                    sys.modules[full] = module
                    break
    except Exception:  # noqa: BLE001 - numba imports scipy.linalg itself then
        return


class _CompileNotice:
    """Whether this process has said that it compiles the package's kernels (once)."""

    shown = False
    registered = False
    text = (
        "affordgrasp: compiling the numba kernels (no usable cache: an editable install, an "
        "edited kernel or another CPU); a few minutes, once - later runs load them from the "
        "cache in about a second"
    )


def _announce_compilation(event) -> None:
    """Say on stderr, once per process, that the package's kernels compile.

    A cache miss costs minutes of silence otherwise. Written to stderr rather than logged:
    it must reach a user who configured no logging, and the CLI's summary line reports the
    cost afterwards.
    """
    if _CompileNotice.shown:
        return
    dispatcher = (event.data or {}).get("dispatcher")
    module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
    if not module.startswith(f"{_PACKAGE_DIR.name}."):
        return
    _CompileNotice.shown = True
    print(_CompileNotice.text, file=sys.stderr, flush=True)


def _install_compile_notice() -> None:
    """Register :func:`_announce_compilation` for numba's ``numba:compile`` event.

    numba broadcasts the event only when a function compiles (after a cache miss), never
    when it loads from the cache. Without numba's event API nothing is announced.
    """
    if _CompileNotice.registered:
        return
    _CompileNotice.registered = True
    try:
        from numba.core import event
    except ImportError:  # pragma: no cover - numba without its event API
        return

    class _Notice(event.Listener):
        def on_start(self, ev):
            _announce_compilation(ev)

        def on_end(self, ev):
            pass

    event.register("numba:compile", _Notice())


_installed: list[type] = []


def install_package_stamp() -> None:
    """Make numba validate this package's cached kernels against all their sources (once).

    Also makes loading them from the cache light (:func:`_install_light_loading`) and a
    compilation announce itself once on stderr (:func:`_install_compile_notice`). The
    first two rely on internals of numba (``caching._CacheLocator`` and the locator list of
    ``caching.CacheImpl``); with a numba that lacks them numba is left alone: its caches
    then follow the modification time of each kernel's own file, as for any numba user.
    """
    if _installed:
        return
    from numba.core import caching

    _install_compile_notice()

    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    if not hasattr(caching, "_CacheLocator") or not hasattr(impl, "_locator_classes"):
        return
    locator = _make_locator_class()
    _cache_impl()._locator_classes.insert(0, locator)
    _install_light_loading(locator)
    _installed.append(locator)
