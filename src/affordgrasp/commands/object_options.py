"""The options that name objects and hands: scale, units, materials, mesh files.

Object specs (a family, ``family:seed`` or a mesh path) resolved with the scale options
applied where they mean something, and refused, saying why, where they do not.
"""

from __future__ import annotations

from ..errors import InputError

HAND_HELP = "barrett (default), parallel_jaw or a .json/.toml hand file"


def add_scale_arguments(p) -> None:
    """``--size-m`` / ``--units`` (mesh files only) and ``--materials`` (families only) for
    every command that takes an object.

    Parameters
    ----------
    p : argparse.ArgumentParser
        Extended in place.
    """
    p.add_argument(
        "--size-m",
        type=float,
        default=None,
        metavar="M",
        help="rescale mesh files so that their longest extent is M metres",
    )
    p.add_argument(
        "--units", default=None, help="length unit of mesh files: m (default), cm, mm, in, ft"
    )
    p.add_argument(
        "--materials",
        action="store_true",
        help="mass properties of the built-in families from their per-part materials (steel, "
        "wood, ...) instead of uniform unit density, the paper's default",
    )


def scale_options(args) -> dict:
    """The scale options of a parsed command line as keyword arguments of ``load_object``.

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    dict
        ``size_m`` and ``units``, None where not given (or the command has no such option).
    """
    return {"size_m": getattr(args, "size_m", None), "units": getattr(args, "units", None)}


def materials_option(args) -> bool:
    """Whether the parsed command line asks for per-part materials (``--materials``).

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    bool
        False when not given (or the command has no such option).
    """
    return bool(getattr(args, "materials", False))


def load_objects(specs, args) -> list:
    """Resolve object specs with ``--size-m`` / ``--units`` applied to the mesh files and
    ``--materials`` to the families.

    Families are built at their real size; the scale options apply to the mesh files among
    ``specs`` and are refused when there is none; ``--materials`` is refused when every
    spec is a mesh file.

    Parameters
    ----------
    specs : sequence of str
        Families, ``family:seed`` or mesh paths.
    args : argparse.Namespace
        The parsed command line (its scale options).

    Returns
    -------
    list of GraspObject
        In the order of ``specs``.

    Raises
    ------
    InputError
        When a scale option is given and every spec is a family.
    """
    from ..objects import load_object
    from ..objects.resolve import is_family_spec

    materials = materials_option(args)
    if materials and not any(is_family_spec(s) for s in specs):
        load_object(specs[0], materials=True)  # refused for a mesh file, saying why
    scale = scale_options(args)
    if all(v is None for v in scale.values()):
        return [load_object(s, materials=materials and is_family_spec(s)) for s in specs]
    if all(is_family_spec(s) for s in specs):
        given = " and ".join(f"--{k.replace('_', '-')}" for k, v in scale.items() if v is not None)
        raise InputError(
            f"{given} rescale mesh files, and {', '.join(map(repr, specs))} "
            + ("is a built-in family" if len(specs) == 1 else "are built-in families")
            + " (made at real size in metres); drop the option or name a mesh file"
        )
    return [
        load_object(s, materials=materials) if is_family_spec(s) else load_object(s, **scale)
        for s in specs
    ]


def check_mesh_files(args) -> None:
    """Refuse ``--mesh`` paths that are not mesh files, and SOURCE files that are neither
    mesh files nor datasets, before any work.

    ``--mesh`` files are read only when a dataset object is not a built-in family, so
    without this check a mistyped path would be ignored in silence.

    Parameters
    ----------
    args : argparse.Namespace
        With a ``mesh`` list and ``source`` (``show``, ``plots``); other commands pass
        through.

    Raises
    ------
    InputError
        Naming the path and what is wrong with it.
    """
    import os

    from ..objects.loading import SUPPORTED_EXTENSIONS

    for path in getattr(args, "source", None) or []:
        ext = os.path.splitext(path)[1].lower()
        if os.path.isfile(path) and ext not in SUPPORTED_EXTENSIONS:
            raise InputError(
                f"SOURCE {path!r} is a file but not a mesh file ({ext or 'no extension'}); give "
                "a dataset directory (the folder of a _manifest.json or of Parquet files), a "
                f"family (e.g. knife) or a mesh file ({', '.join(SUPPORTED_EXTENSIONS)})"
            )
    for path in getattr(args, "mesh", None) or []:
        if not os.path.isfile(path):
            what = "is a directory" if os.path.isdir(path) else "does not exist"
            raise InputError(f"--mesh {path!r} {what}; give the mesh file of a dataset object")
        ext = os.path.splitext(path)[1].lower()
        if ext not in SUPPORTED_EXTENSIONS:
            raise InputError(
                f"--mesh {path!r} is not a mesh file ({ext or 'no extension'}); supported "
                f"formats: {', '.join(SUPPORTED_EXTENSIONS)}"
            )
