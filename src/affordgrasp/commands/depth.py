"""``affordgrasp depth``: the camera-in-hand depth image D(p0, O) of one pregrasp."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..runtime.writing import atomic_write
from .limits import MAX_SEED, OWN_CHECK, SEED_BITS

MAX_PNG_SIDE = 4096  # pixels: the process peaks near 450 MB drawing it
# Of the numeric options: see limits.check_limits.
LIMITS = {
    "sample": (None, MAX_SEED, "sample numbers are 64-bit"),
    "seed": SEED_BITS,
    **dict.fromkeys(("size", "fov", "scale"), OWN_CHECK),  # DepthCamera; the PNG's side
}


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp depth`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    p.add_argument("object", help="family (knife), family:seed (knife:7) or a mesh path")
    which = p.add_mutually_exclusive_group()
    which.add_argument(
        "--p0",
        default=None,
        metavar="U1,U2,U3,U4,U5,S",
        help="the pregrasp: six comma-separated numbers in [-1,1]^5 x [0,1]",
    )
    which.add_argument(
        "--sample",
        type=int,
        default=None,
        metavar="I",
        help="the pregrasp of sample I of a generated run (with --seed); default sample 0",
    )
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        help="seed of --sample (default 0; a dataset row: its seed column)",
    )
    p.add_argument(
        "-o",
        "--out",
        default=None,
        metavar="FILE",
        help="write the image: .npy (float32 m, 0 = no return) or .png (colour-mapped view)",
    )
    p.add_argument("--size", type=int, default=128, help="image side, pixels (default 128)")
    p.add_argument("--fov", type=float, default=60.0, help="field of view, degrees (default 60)")
    p.add_argument("--scale", type=int, default=2, help="PNG upscaling factor (default 2)")
    p.add_argument(
        "--sensor",
        action="store_true",
        help="as a depth sensor would return it (noise, returns lost at grazing angles and "
        "at random; seeded by --seed and the sample); default: the exact image",
    )


def parse_p0(text: str) -> np.ndarray:
    """The ``--p0`` option: six comma-separated numbers.

    Parameters
    ----------
    text : str
        ``"u1,u2,u3,u4,u5,s"``.

    Returns
    -------
    (1, 6) float64 ndarray

    Raises
    ------
    InputError
        When it is not six numbers.
    """
    try:
        values = [float(v) for v in text.replace(" ", "").split(",")]
    except ValueError:
        raise InputError(f"--p0 {text!r} is not six comma-separated numbers") from None
    if len(values) != 6:
        raise InputError(f"--p0 needs six numbers (u1,u2,u3,u4,u5,s), got {len(values)}")
    return np.array([values])


def run(args, out) -> None:
    """Run ``affordgrasp depth``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..grasp.pregrasp import sample_inputs
    from ..objects import load_object
    from ..vision import DepthCamera, renderer_for, save_depth_png

    if args.out is not None and not args.out.endswith((".png", ".npy")):
        raise InputError(f"--out {args.out!r} must end in .png or .npy")
    if args.out is not None:
        from .output_files import check_output_file

        check_output_file(args.out, "--out")
    if args.scale < 1:
        raise InputError(f"--scale must be >= 1, got {args.scale}")
    if args.p0 is not None:
        p0 = parse_p0(args.p0)
    else:
        i = args.sample or 0
        if i < 0:
            raise InputError(f"--sample must be >= 0, got {i}")
        p0, _ = sample_inputs(args.seed, i, i + 1)
    camera = DepthCamera(size=args.size, fov_deg=args.fov)
    if args.size * args.scale > MAX_PNG_SIDE:  # the upscaled PNG is made in memory, 3 B/px
        raise InputError(
            f"--scale {args.scale} makes a PNG {args.size * args.scale:,} pixels wide; at most "
            f"{MAX_PNG_SIDE:,}: with --size {args.size}, use --scale at most "
            f"{max(1, MAX_PNG_SIDE // args.size)}"
        )
    obj = load_object(args.object)
    renderer = renderer_for(obj, camera)
    depth = renderer.render(p0)
    if args.sensor:
        from ..vision.sensor import SensorModel, apply_sensor

        depth = apply_sensor(depth, SensorModel(seed=args.seed), [args.sample or 0], camera)
    depth = depth[0]
    pose = renderer.poses(p0)[0]
    if args.out is not None:
        if args.out.endswith(".npy"):
            atomic_write(args.out, lambda fh: np.save(fh, depth))
        else:
            save_depth_png(args.out, depth, scale=args.scale)
    hit = depth > 0
    facts = {
        "object": obj.name,
        "p0": p0[0].tolist(),
        "size": camera.size,
        "fov_deg": camera.fov_deg,
        "camera_position_m": pose[:3, 3].tolist(),
        "optical_axis": pose[:3, 2].tolist(),
        "object_length_m": renderer.frame.length,
        "pixels_hit": int(hit.sum()),
        "depth_min_m": float(depth[hit].min()) if hit.any() else None,
        "depth_max_m": float(depth[hit].max()) if hit.any() else None,
        "out": args.out,
    }
    out.table(
        f"Depth image of {obj.name}",
        ["quantity", "value"],
        [
            ["p0", ", ".join(f"{v:.3f}" for v in p0[0])],
            ["image", f"{camera.size}x{camera.size}, {camera.fov_deg:g} deg"],
            ["camera at (m)", ", ".join(f"{v:.4f}" for v in pose[:3, 3])],
            ["object length (m)", renderer.frame.length],
            ["pixels with a return", f"{int(hit.sum())} of {hit.size}"],
            [
                "depth range (m)",
                "-" if not hit.any() else f"{depth[hit].min():.4f} .. {depth[hit].max():.4f}",
            ],
            ["written", args.out or "-"],
        ],
    )
    out.result(facts)
