"""``affordgrasp objects``: list the built-in families, or export one as a mesh file."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import InputError
from . import add_verbose_argument
from .limits import SEED, SIZE_M
from .object_options import add_scale_arguments, load_objects

LIMITS = {"seed": SEED, "size_m": SIZE_M}  # of the numeric options: see limits.check_limits


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp objects`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    sub = p.add_subparsers(dest="action", metavar="ACTION")
    listing = sub.add_parser("list", help="list the families (the default)")
    e = sub.add_parser("export", help="write one object as a mesh file (OBJ, STL, PLY, GLB, OFF)")
    e.add_argument("object", help="family, family:seed, or a mesh path")
    e.add_argument("--seed", type=int, default=None, help="family seed (same as family:SEED)")
    e.add_argument("-o", "--out", required=True, help="output file; the extension sets the format")
    add_scale_arguments(e)
    # --json also after the action (the parent parser has it too).
    for q in (listing, e):
        q.add_argument(
            "--json", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS
        )
        add_verbose_argument(q)


def run(args, out) -> None:
    """Run ``affordgrasp objects``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..objects import FAMILIES

    if getattr(args, "action", None) == "export":
        spec = args.object
        if args.seed is not None:
            if ":" in spec:
                raise InputError(f"give the seed once: either {spec!r} or --seed, not both")
            spec = f"{spec}:{args.seed}"
        from .output_files import check_output_file

        check_output_file(args.out, "-o")
        path = Path(args.out)
        ext = path.suffix.lower().lstrip(".")
        if ext not in ("obj", "stl", "ply", "glb", "off"):
            raise InputError(f"cannot write {path.name!r}: use .obj, .stl, .ply, .glb or .off")
        (obj,) = load_objects([spec], args)
        from ..runtime.writing import atomic_write

        data = obj.mesh.export(file_type=ext)
        atomic_write(path, data.encode() if isinstance(data, str) else data)
        m = obj.mass
        ext_m = m.bounds[1] - m.bounds[0]
        out.text(
            f"wrote {path} ({obj.name}, {len(obj.mesh.faces)} triangles, "
            f"{ext_m[0]:.3f} x {ext_m[1]:.3f} x {ext_m[2]:.3f} m)"
        )
        out.result(
            {
                "object": obj.name,
                "category": obj.category,
                "path": str(path),
                "triangles": len(obj.mesh.faces),
                "extent_m": ext_m,
                "volume_m3": m.volume,
                "mesh_hash": obj.mesh_hash,
            }
        )
        return
    rows = [[f.name, f.category, f.description] for f in FAMILIES.values()]
    out.table("built-in object families", ["name", "category", "description"], rows)
    out.text("name an object as FAMILY (seed 0), FAMILY:SEED, or a mesh path")
    out.result({"families": [dict(name=r[0], category=r[1], description=r[2]) for r in rows]})
