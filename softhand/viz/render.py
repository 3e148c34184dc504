"""Offscreen pictures of the handshake scene (``mujoco.Renderer``), written as PNG.

:func:`render_state` draws one state of the scene (both hands and MuJoCo's contact points) from a
free camera around the hands; :func:`render_sheet` draws several moments from the back of each
hand and from below, the prosthetic's regions coloured by their force. The caller hands the states
over as plain arrays (``qpos`` and the mocap poses), as for the rerun recording, so this stage
does not import the environment.

Needs an OpenGL context, chosen when mujoco is first imported: set ``MUJOCO_GL=egl`` (or
``osmesa``) before that (``softhand render`` does). Tests do not render.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from softhand.io import atomic_open, check_writable_file

__all__ = ["HAND_COLOURS", "SHEET_VIEWS", "CameraView", "SheetFrame", "render_sheet",
           "render_state"]

#: Background of every picture (RGB, 0-255): light, so that pictures print and read in documents.
BACKGROUND = (244, 244, 240)
#: Colour of MuJoCo's contact-point markers in a picture (RGBA, 0-1): dark magenta on any skin.
CONTACT_COLOUR = (0.75, 0.0, 0.55, 1.0)
#: Colour of each hand's soft geoms in a picture (by name prefix): prosthetic skin, partner tissue.
HAND_COLOURS = {"pro_skin_": (0.95, 0.62, 0.32, 0.85), "hum_tissue_": (0.25, 0.5, 0.9, 0.8)}


@dataclass(frozen=True)
class CameraView:
    """A free camera around the scene.

    Attributes:
        lookat: point the camera looks at (m, world frame); None: the mean of the two hands'
            body positions.
        distance_m: distance from ``lookat`` (m), > 0.
        azimuth_deg, elevation_deg: MuJoCo's free-camera angles (deg).
    """

    lookat: tuple[float, float, float] | None = None
    distance_m: float = 0.42
    azimuth_deg: float = 150.0
    elevation_deg: float = -30.0


def render_state(model: mujoco.MjModel, qpos: np.ndarray, mocap_pos: np.ndarray,
                 mocap_quat: np.ndarray, path: str | os.PathLike, *, width: int = 960,
                 height: int = 720, view: CameraView | None = None,
                 contacts: bool = True, caption: str | None = None) -> Path:
    """Render one state of the scene to a PNG at ``path`` (written atomically); return the path.
    The two hands get HAND_COLOURS, on a light BACKGROUND; ``caption``: a line of text under the
    picture (e.g. which hand is which and when).

    Raises:
        ValueError: a state that does not fit the model, a size outside [64, 4096] pixels or a
            path that is not a writable ``.png``.
    """
    target = check_writable_file(path, suffix=".png")
    _check_size(width, height)
    data = _state(model, qpos, mocap_pos, mocap_quat)
    pixels = _render(model, data, view or CameraView(), width, height, contacts,
                     _prefix_colours(model))
    _save(target, pixels, caption)
    return target


@dataclass(frozen=True)
class SheetFrame:
    """One moment of a contact sheet: the state, its label and each skin region's force.

    Attributes:
        qpos, mocap_pos, mocap_quat: the state.
        label: e.g. "grip, t = 1.05 s".
        region_force_N: skin geom name -> force (N); the geom is coloured by force_colors().
    """

    qpos: np.ndarray
    mocap_pos: np.ndarray
    mocap_quat: np.ndarray
    label: str
    region_force_N: dict[str, float]


#: The views of a contact sheet: from the back of each hand and from below.
SHEET_VIEWS = {"back of the prosthetic hand": (90.0, -5.0),
               "back of the partner's hand": (270.0, -5.0),
               "from below": (180.0, 75.0)}


def render_sheet(model: mujoco.MjModel, frames: list[SheetFrame], path: str | os.PathLike, *,
                 size: int = 480, distance_m: float = 0.3, contacts: bool = True) -> Path:
    """A contact sheet (PNG, atomic): one row per frame, one column per SHEET_VIEWS view, looking at
    the midpoint of the two palms. The prosthetic's skin regions are coloured by their force
    (softhand.viz.recording.force_colors: grey to blue under 2 N, orange to red over), its other
    skin grey, the partner's tissue green; MuJoCo's contact points shown."""
    from softhand.viz.recording import force_colors

    target = check_writable_file(path, suffix=".png")
    _check_size(size, size)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(frames), len(SHEET_VIEWS), squeeze=False,
                             figsize=(3.2 * len(SHEET_VIEWS), 3.3 * len(frames)))
    for row, frame in zip(axes, frames, strict=True):
        data = _state(model, frame.qpos, frame.mocap_pos, frame.mocap_quat)
        palms = [model.body(b).id for b in ("pro_palm", "hum_palm")]
        lookat = tuple(np.mean(data.xpos[palms], axis=0))
        colours = {}
        for g in range(model.ngeom):
            name = model.geom(g).name
            if name.startswith("hum_tissue_"):
                colours[g] = (0.45, 0.75, 0.4, 0.75)
            elif name.startswith("pro_skin_"):
                f = frame.region_force_N.get(name)
                colours[g] = ((0.75, 0.75, 0.75, 0.9) if f is None
                              else tuple(force_colors(f) / 255.0))
        for ax, (title, (az, el)) in zip(row, SHEET_VIEWS.items(), strict=True):
            view = CameraView(lookat=lookat, distance_m=distance_m, azimuth_deg=az,
                              elevation_deg=el)
            ax.imshow(_render(model, data, view, size, size, contacts, colours))
            ax.set_title(f"{frame.label}\n{title}", fontsize=9)
            ax.axis("off")
    fig.text(0.5, 0.005, "prosthetic skin by force: grey-blue < 2 N, orange-red > 2 N (red 5 N); "
             "partner's tissue green; contact points magenta", ha="center", fontsize=8)
    fig.tight_layout(rect=(0, 0.02, 1, 1))
    with atomic_open(target, "wb") as fh:
        fig.savefig(fh, format="png", dpi=100)
    plt.close(fig)
    return target


def _check_size(width: int, height: int) -> None:
    for name, v in (("width", width), ("height", height)):
        if not 64 <= v <= 4096:
            raise ValueError(f"{name} = {v!r}: allowed 64-4096 pixels")


def _state(model: mujoco.MjModel, qpos, mocap_pos, mocap_quat) -> mujoco.MjData:
    if np.shape(qpos) != (model.nq,):
        raise ValueError(f"qpos has shape {np.shape(qpos)}; the model has nq = {model.nq}")
    if np.shape(mocap_pos) != (model.nmocap, 3) or np.shape(mocap_quat) != (model.nmocap, 4):
        raise ValueError(f"mocap poses have shapes {np.shape(mocap_pos)}, {np.shape(mocap_quat)};"
                         f" the model has nmocap = {model.nmocap}")
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    data.mocap_pos[:] = mocap_pos
    data.mocap_quat[:] = mocap_quat
    mujoco.mj_forward(model, data)
    return data


def _prefix_colours(model: mujoco.MjModel) -> dict[int, tuple[float, ...]]:
    out = {}
    for g in range(model.ngeom):
        for prefix, colour in HAND_COLOURS.items():
            if model.geom(g).name.startswith(prefix):
                out[g] = colour
    return out


def _render(model: mujoco.MjModel, data: mujoco.MjData, view: CameraView, width: int,
            height: int, contacts: bool, colours: dict[int, tuple[float, ...]]) -> np.ndarray:
    """Pixels of one view, the geoms in ``colours`` recoloured for this picture only."""
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = (np.mean(data.xpos[1:], axis=0) if view.lookat is None
                     else np.asarray(view.lookat, dtype=float))
    cam.distance, cam.azimuth, cam.elevation = (view.distance_m, view.azimuth_deg,
                                                view.elevation_deg)
    opt = mujoco.MjvOption()
    opt.flags[mujoco.mjtVisFlag.mjVIS_CONTACTPOINT] = contacts
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
    model.vis.global_.offheight = max(model.vis.global_.offheight, height)
    model.vis.scale.contactwidth = 0.05  # contact points as small discs (scaled by extent)
    model.vis.scale.contactheight = 0.01
    rgba = model.geom_rgba.copy()
    point = model.vis.rgba.contactpoint.copy()
    for g, colour in colours.items():
        model.geom_rgba[g] = colour
    model.vis.rgba.contactpoint[:] = CONTACT_COLOUR
    try:
        with mujoco.Renderer(model, height, width) as renderer:
            renderer.update_scene(data, camera=cam, scene_option=opt)
            pixels = renderer.render()
            renderer.enable_segmentation_rendering()
            seg = renderer.render()
            renderer.disable_segmentation_rendering()
    finally:
        model.geom_rgba[:] = rgba
        model.vis.rgba.contactpoint[:] = point
    # a light background: the pixels no object covers (segmentation id -1 and still the clear
    # colour; contact markers are decorations without an id, so the colour test keeps them)
    empty = (seg[..., 0] < 0) & (pixels.max(axis=-1) == 0)
    pixels = pixels.copy()
    pixels[empty] = BACKGROUND
    return pixels


def _save(target: Path, pixels: np.ndarray, caption: str | None = None) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if caption is None:
        with atomic_open(target, "wb") as fh:
            plt.imsave(fh, pixels, format="png")
        return
    h, w = pixels.shape[:2]
    band = 36  # pixels of caption under the picture
    fig = plt.figure(figsize=(w / 100, (h + band) / 100), dpi=100)
    fig.patch.set_facecolor(np.asarray(BACKGROUND) / 255)
    ax = fig.add_axes((0, band / (h + band), 1, h / (h + band)))
    ax.imshow(pixels)
    ax.axis("off")
    fig.text(0.5, 0.5 * band / (h + band), caption, ha="center", va="center", fontsize=11)
    with atomic_open(target, "wb") as fh:
        fig.savefig(fh, format="png", dpi=100, facecolor=fig.get_facecolor())
    plt.close(fig)
