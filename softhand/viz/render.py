"""Offscreen pictures of the handshake scene, written as PNG.

`render_state` draws one state of the scene (both hands and MuJoCo's contact points) from a
free camera around the hands, the prosthetic's skin in one colour or by force; `render_sheet`
draws several moments from the back of each hand and from below, the prosthetic's regions
coloured by their force. The caller hands the states over as plain arrays (``qpos`` and the
mocap poses), as for the rerun recording. The picture itself is made by
`softhand.envs.picture.ScenePicture`, the one place for it, which the env's ``render()`` uses
too.

Needs an OpenGL context, chosen when mujoco is first imported: set ``MUJOCO_GL=egl`` (or
``osmesa``) before that (``softhand render`` does).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from softhand.envs.picture import (
    BACKGROUND,
    HAND_COLOURS,
    CameraView,
    ScenePicture,
    check_size,
    force_colors,
    posed_data,
    region_colours,
)
from softhand.io import atomic_open, check_writable_file

__all__ = ["HAND_COLOURS", "SHEET_VIEWS", "CameraView", "SheetFrame", "render_sheet",
           "render_state", "write_video"]


def render_state(model: mujoco.MjModel, qpos: np.ndarray, mocap_pos: np.ndarray,
                 mocap_quat: np.ndarray, path: str | os.PathLike, *, width: int = 960,
                 height: int = 720, view: CameraView | None = None,
                 contacts: bool = True, caption: str | None = None,
                 region_force_N: dict[str, float] | None = None) -> Path:
    """Render one state of the scene to a PNG at ``path`` (written atomically); return the path.
    The two hands get HAND_COLOURS, on a light BACKGROUND; with ``region_force_N`` (skin geom
    name -> N) the prosthetic's skin is coloured by force instead, as in `render_sheet`;
    ``caption``: a line of text under the picture (e.g. which hand is which and when).

    Raises:
        ValueError: a state that does not fit the model, a size outside [64, 4096] pixels or a
            path that is not a writable ``.png``.
    """
    target = check_writable_file(path, suffix=".png")
    check_size(width, height)
    data = posed_data(model, qpos, mocap_pos, mocap_quat)
    colours = None if region_force_N is None else region_colours(model, region_force_N)
    with ScenePicture(model, width, height) as picture:
        pixels = picture.draw(data, view or CameraView(), contacts=contacts, colours=colours)
    _save(target, pixels, caption)
    return target


@dataclass(frozen=True)
class SheetFrame:
    """One moment of a contact sheet: the state, its label and each skin region's force.

    Attributes:
        qpos, mocap_pos, mocap_quat: the state.
        label: e.g. "grip, t = 1.05 s".
        region_force_N: skin geom name -> force (N); the geom is coloured by region_colours().
    """

    qpos: np.ndarray
    mocap_pos: np.ndarray
    mocap_quat: np.ndarray
    label: str
    region_force_N: dict[str, float]


#: The views of a contact sheet: from the back of each hand, from below and from the thumb side
#: (above: both thumbs point up).
SHEET_VIEWS = {"back of the prosthetic hand": (90.0, -5.0),
               "back of the partner's hand": (270.0, -5.0),
               "from below": (180.0, 75.0),
               "from the thumb side": (180.0, -75.0)}


def render_sheet(model: mujoco.MjModel, frames: list[SheetFrame], path: str | os.PathLike, *,
                 size: int = 480, distance_m: float = 0.3, contacts: bool = True) -> Path:
    """A contact sheet (PNG, atomic): one row per frame, one column per SHEET_VIEWS view, looking at
    the midpoint of the two palms. The prosthetic's skin regions are coloured by their force
    (softhand.envs.picture.region_colours: pale to mid grey under 2 N, orange to red over), its
    other skin grey, the partner's tissue blue (HAND_COLOURS, as in every picture); MuJoCo's
    contact points shown (they lie inside the pressed skins, so few show), and a colour bar of
    the force in N under the sheet."""
    target = check_writable_file(path, suffix=".png")
    check_size(size, size)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(frames), len(SHEET_VIEWS), squeeze=False,
                             figsize=(3.2 * len(SHEET_VIEWS), 3.3 * len(frames)))
    with ScenePicture(model, size, size) as picture:
        for row, frame in zip(axes, frames, strict=True):
            data = posed_data(model, frame.qpos, frame.mocap_pos, frame.mocap_quat)
            palms = [model.body(b).id for b in ("pro_palm", "hum_palm")]
            lookat = tuple(np.mean(data.xpos[palms], axis=0))
            colours = region_colours(model, frame.region_force_N)
            for ax, (title, (az, el)) in zip(row, SHEET_VIEWS.items(), strict=True):
                view = CameraView(lookat=lookat, distance_m=distance_m, azimuth_deg=az,
                                  elevation_deg=el)
                ax.imshow(picture.draw(data, view, contacts=contacts, colours=colours))
                ax.set_title(f"{frame.label}\n{title}", fontsize=9)
                ax.axis("off")
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    _force_scale(fig, [0.25, 0.05, 0.5, 0.012],
                 "prosthetic skin by its region's force, N (a skin of several zones, the palm: its "
                 "largest); the partner's hand blue")
    with atomic_open(target, "wb") as fh:
        fig.savefig(fh, format="png", dpi=100)
    plt.close(fig)
    return target


def _force_scale(fig, rect: list[float], label: str, top_N: float = 6.0) -> None:
    """A colour bar of `force_colors` (N) in ``fig`` at ``rect`` (figure fractions), so that a
    picture's force can be read, not only its side of 2 N."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import ListedColormap, Normalize

    levels = np.linspace(0.0, top_N, 256)
    cmap = ListedColormap(force_colors(levels) / 255.0)
    bar = fig.colorbar(ScalarMappable(norm=Normalize(0.0, top_N), cmap=cmap),
                       cax=fig.add_axes(rect), orientation="horizontal",
                       ticks=np.arange(0.0, top_N + 0.5, 1.0))
    bar.ax.tick_params(labelsize=7)
    bar.ax.set_xticklabels([f"{t:g}" if t < top_N else f"{t:g}+" for t in bar.get_ticks()])
    bar.set_label(label, fontsize=8)


def write_video(frames: list[np.ndarray], path: str | os.PathLike, *, fps: float) -> Path:
    """An animated GIF (atomic) of ``frames`` ((H, W, 3) uint8 pictures, e.g. the env's
    ``render()``) at ``fps`` frames per second, looping; one palette for all frames (adaptive,
    from up to 16 of them), so the hands keep their colours from frame to frame.

    Raises:
        ValueError: no frames, frames of different sizes, ``fps`` outside (0, 100] or a path
            that is not a writable ``.gif``.
    """
    target = check_writable_file(path, suffix=".gif")
    if not frames:
        raise ValueError("frames: expected at least one picture")
    if len({f.shape for f in frames}) != 1:
        raise ValueError(f"frames: expected pictures of one size, got {sorted({f.shape for f in frames})}")
    if not (isinstance(fps, (int, float)) and 0 < fps <= 100):
        raise ValueError(f"fps = {fps!r}: expected a number in (0, 100]")
    from PIL import Image

    sample = frames[::max(1, len(frames) // 16)]
    mosaic = np.concatenate([np.asarray(f, np.uint8)[::2, ::2] for f in sample])
    palette = Image.fromarray(mosaic).quantize(colors=255)
    images = [Image.fromarray(np.asarray(f, np.uint8)).quantize(palette=palette) for f in frames]
    with atomic_open(target, "wb") as fh:
        images[0].save(fh, format="GIF", save_all=True, append_images=images[1:],
                       duration=round(1000.0 / fps), loop=0, optimize=False)
    return target


def _save(target: Path, pixels: np.ndarray, caption: str | None = None) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if caption is None:
        with atomic_open(target, "wb") as fh:
            plt.imsave(fh, pixels, format="png")
        return
    import textwrap

    h, w = pixels.shape[:2]
    # wrapped to the picture's width (11 pt: at most 8 pixels a character), 18 pixels a line
    lines = textwrap.wrap(caption, width=max(20, w // 8))
    caption = "\n".join(lines)
    band = 18 * len(lines) + 18  # pixels of caption under the picture
    fig = plt.figure(figsize=(w / 100, (h + band) / 100), dpi=100)
    fig.patch.set_facecolor(np.asarray(BACKGROUND) / 255)
    ax = fig.add_axes((0, band / (h + band), 1, h / (h + band)))
    ax.imshow(pixels)
    ax.axis("off")
    fig.text(0.5, 0.5 * band / (h + band), caption, ha="center", va="center", fontsize=11)
    with atomic_open(target, "wb") as fh:
        fig.savefig(fh, format="png", dpi=100, facecolor=fig.get_facecolor())
    plt.close(fig)
