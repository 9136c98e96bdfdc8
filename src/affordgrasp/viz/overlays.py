"""Overlays drawn over a render: contacts, normals, friction cones, use point, wrist axis.

Markers are placed by projecting their 3D points with the render's camera; markers hidden
behind a surface are drawn hollow.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .camera import Camera, any_perpendicular, unit
from .raycast import Render, auto_camera, caster_of, visible
from .scene import GraspScene


@dataclass(frozen=True)
class OverlayStyle:
    """What is drawn over the image, and how big (sizes in points at 100 dpi).

    Attributes
    ----------
    contacts, normals, cones, use_point, wrist_axis, center_of_mass : bool
        Which overlays are drawn.
    marker_size : float
        Points.
    line_width : float
        Points.
    normal_length : float
        Length of the normal arrows, a fraction of the scene size.
    """

    contacts: bool = True
    normals: bool = True
    cones: bool = False
    use_point: bool = True
    wrist_axis: bool = True
    center_of_mass: bool = True
    marker_size: float = 6.0
    line_width: float = 1.8
    normal_length: float = 0.10  # fraction of the scene size


CONTACT_COLOR = "#ff8c00"
CONE_COLOR = "#e0a030"
USE_COLOR = "#d62728"
WRIST_COLOR = "#2ca02c"
COM_COLOR = "#111111"


def draw_grasp(
    ax,
    scene: GraspScene,
    *,
    camera: Camera | None = None,
    style: OverlayStyle = OverlayStyle(),
    width: int = 512,
    height: int = 512,
) -> Render:
    """Render ``scene`` into the matplotlib axes ``ax`` (image + overlays).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    scene : GraspScene
    camera : Camera, optional
        :func:`affordgrasp.viz.raycast.auto_camera` when None.
    style : OverlayStyle
    width, height : int
        Pixels (rendered with 2 x 2 rays each).

    Returns
    -------
    Render
    """
    caster = caster_of(scene)
    if camera is None:
        camera = auto_camera(scene, width=width, height=height)
    render = caster.render(camera, supersample=2)
    ax.imshow(render.rgb, interpolation="antialiased")
    ax.set_xlim(0, camera.width)
    ax.set_ylim(camera.height, 0)
    ax.set_axis_off()
    draw_overlays(ax, scene, render, caster=caster, style=style)
    return render


def draw_overlays(
    ax, scene: GraspScene, render: Render, *, caster=None, style: OverlayStyle = OverlayStyle()
) -> None:
    """Draw contacts, normals, cones, use point, wrist axis and centre of mass over ``render``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    scene : GraspScene
    render : Render
        The image drawn in ``ax`` (its camera projects the overlays).
    caster : SceneCaster, optional
        For hiding occluded marks; the scene's when None.
    style : OverlayStyle
    """
    camera = render.camera
    caster = caster_of(scene) if caster is None else caster
    length = style.normal_length * scene.size
    lw = style.line_width
    ms = style.marker_size

    def seg(p, q, **kw):
        uv, _ = camera.project(np.array([p, q]))
        if np.all(np.isfinite(uv)):
            ax.plot(uv[:, 0], uv[:, 1], solid_capstyle="round", **kw)

    def arrow(p, n, color, z):
        uv, _ = camera.project(np.array([p, p + length * n]))
        if np.all(np.isfinite(uv)):
            ax.annotate(
                "",
                xy=tuple(uv[1]),
                xytext=tuple(uv[0]),
                arrowprops=dict(
                    arrowstyle="-|>",
                    color=color,
                    lw=lw,
                    mutation_scale=8 + 2 * lw,
                    shrinkA=0,
                    shrinkB=0,
                ),
                zorder=z,
            )

    if (
        style.wrist_axis
        and np.all(np.isfinite(scene.wrist_point))
        and np.all(np.isfinite(scene.wrist_axis))
    ):
        a = unit(scene.wrist_axis)
        seg(
            scene.wrist_point - 0.3 * scene.size * a,
            scene.wrist_point + 0.4 * scene.size * a,
            color=WRIST_COLOR,
            lw=lw,
            ls=(0, (4, 2)),
            zorder=3,
        )
        _marker(ax, camera, caster, scene.wrist_point[None], WRIST_COLOR, "s", ms * 0.9, z=4)

    k = len(scene.contact_points)
    if style.cones and k:
        ring = np.linspace(0, 2 * np.pi, 25)
        for p, n, mu in zip(
            scene.contact_points, scene.contact_normals, scene.contact_mu, strict=False
        ):
            n = unit(n)
            t1 = any_perpendicular(n)
            t2 = np.cross(n, t1)
            h = 0.8 * length
            r = h * float(mu)
            circle = p + h * n + r * (np.cos(ring)[:, None] * t1 + np.sin(ring)[:, None] * t2)
            uv, _ = camera.project(circle)
            if np.all(np.isfinite(uv)):
                ax.plot(uv[:, 0], uv[:, 1], color=CONE_COLOR, lw=0.8 * lw, alpha=0.9, zorder=5)
            for j in range(0, 24, 6):
                seg(p, circle[j], color=CONE_COLOR, lw=0.8 * lw, alpha=0.9, zorder=5)
    if style.normals and k:
        for p, n in zip(scene.contact_points, scene.contact_normals, strict=False):
            arrow(p, unit(n), CONTACT_COLOR, 6)
    if style.contacts and k:
        _marker(ax, camera, caster, scene.contact_points, CONTACT_COLOR, "o", ms, z=7)

    if style.center_of_mass and np.all(np.isfinite(scene.center_of_mass)):
        uv, _ = camera.project(scene.center_of_mass[None])
        if np.all(np.isfinite(uv)):
            ax.plot(
                uv[:, 0],
                uv[:, 1],
                marker="P",
                ms=ms * 1.1,
                color="white",
                mec=COM_COLOR,
                mew=1.2,
                zorder=8,
                ls="none",
            )

    if style.use_point and np.all(np.isfinite(scene.use_point)):
        if np.all(np.isfinite(scene.use_normal)):
            arrow(scene.use_point, unit(scene.use_normal), USE_COLOR, 8)
        _marker(ax, camera, caster, scene.use_point[None], USE_COLOR, "o", ms * 1.2, z=9)


def _marker(ax, camera, caster, points, color, marker, size, z) -> None:
    """Markers at ``points``: filled where seen, hollow where hidden behind a surface."""
    uv, _ = camera.project(points)
    ok = np.all(np.isfinite(uv), axis=1)
    if not np.any(ok):
        return
    seen = visible(caster, camera, points[ok])
    uv = uv[ok]
    if np.any(seen):
        ax.plot(
            uv[seen, 0],
            uv[seen, 1],
            ls="none",
            marker=marker,
            ms=size,
            color=color,
            mec="black",
            mew=0.8,
            zorder=z,
        )
    if np.any(~seen):
        ax.plot(
            uv[~seen, 0],
            uv[~seen, 1],
            ls="none",
            marker=marker,
            ms=size,
            mfc="none",
            mec=color,
            mew=1.6,
            zorder=z,
        )


def grasp_image(
    scene: GraspScene,
    *,
    size_px: int = 512,
    camera: Camera | None = None,
    style: OverlayStyle = OverlayStyle(),
    caption: str | None = None,
) -> tuple[np.ndarray, Camera]:
    """One grasp drawn in a square image.

    Parameters
    ----------
    scene : GraspScene
    size_px : int
    camera : Camera, optional
    style : OverlayStyle
    caption : str, optional
        Written in the top-left corner (default: the scene's title).

    Returns
    -------
    rgb : (size, size, 3) uint8 ndarray
    camera : Camera
        The camera used.
    """
    from .figure import figure_pixels, new_figure

    caption = scene.title if caption is None else caption
    if camera is not None and (camera.width, camera.height) != (size_px, size_px):
        camera = camera.with_size(size_px, size_px)
    fig, ax = new_figure(size_px, size_px)
    scale = size_px / 512.0
    style = replace(
        style,
        marker_size=style.marker_size * max(scale, 0.6),
        line_width=style.line_width * max(scale, 0.6),
    )
    render = draw_grasp(ax, scene, camera=camera, style=style, width=size_px, height=size_px)
    if caption:
        ax.text(
            0.02,
            0.98,
            caption,
            transform=ax.transAxes,
            va="top",
            ha="left",
            fontsize=max(6.5, 9.0 * scale),
            zorder=20,
            bbox=dict(boxstyle="round,pad=0.25", fc="white", ec="none", alpha=0.8),
        )
    return figure_pixels(fig), render.camera


def save_grasp_png(
    scene: GraspScene,
    path,
    *,
    size_px: int = 512,
    camera: Camera | None = None,
    style: OverlayStyle = OverlayStyle(),
    caption: str | None = None,
) -> Camera:
    """Render one grasp (image, overlays, caption) to a square PNG.

    Parameters
    ----------
    scene : GraspScene
    path : path
        The PNG file.
    size_px, camera, style, caption
        As for :func:`grasp_image`.

    Returns
    -------
    Camera
        The camera used.
    """
    from .figure import save_image

    rgb, camera = grasp_image(scene, size_px=size_px, camera=camera, style=style, caption=caption)
    save_image(rgb, path)
    return camera
