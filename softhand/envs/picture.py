"""The scene's picture: one offscreen ``mujoco.Renderer`` draw of a state of the two hands.

One place for how a picture is made, used by the env's ``render()`` (``render_mode="rgb_array"``)
and by `softhand.viz.render` (``softhand render``'s PNG and contact sheets): a free camera
around the hands (`CameraView`), MuJoCo's contact points, the geoms recoloured for the
picture only (the hands by `HAND_COLOURS`, or the caller's colours), and a light
`BACKGROUND` where no object is drawn (from the segmentation render).

Needs an OpenGL context, chosen when mujoco is first imported: set ``MUJOCO_GL=egl`` (or
``osmesa``) before that (``softhand render`` does).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from softhand.hands.prosthetic import regions
from softhand.laws.fit import REFERENCE_FORCE_N

__all__ = ["BACKGROUND", "CONTACT_COLOUR", "HAND_COLOURS", "RENDER_VIEW", "STANDOUT_FORCE_N",
           "CameraView", "ScenePicture", "check_size", "force_colors", "hand_colours",
           "posed_data", "region_colours"]

#: Background of every picture (RGB, 0-255): light, so that pictures print and read in documents.
BACKGROUND = (244, 244, 240)
#: Colour of MuJoCo's contact-point markers in a picture (RGBA, 0-1): dark magenta on any skin.
CONTACT_COLOUR = (0.75, 0.0, 0.55, 1.0)
#: Colour of each hand's soft geoms in a picture (by name prefix): prosthetic skin, partner tissue.
HAND_COLOURS = {"pro_skin_": (0.95, 0.62, 0.32, 0.85), "hum_tissue_": (0.25, 0.5, 0.9, 0.8)}
#: Fig. 4 of the paper marks the regions whose handshake force exceeds 2 N
#: (``paper()["handshake"]["over_2N"]``); above it the force colours turn warm.
STANDOUT_FORCE_N = REFERENCE_FORCE_N
#: Force colour ramps (RGB): 0 N -> STANDOUT_FORCE_N pale to mid grey; above it orange to red.
_COOL = (np.array([225.0, 222.0, 215.0]), np.array([115.0, 118.0, 125.0]))
_WARM = (np.array([255.0, 170.0, 0.0]), np.array([200.0, 0.0, 0.0]))
#: Picture sizes allowed (pixels, each side).
SIZE_RANGE = (64, 4096)


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


#: ``softhand render``'s default view (``--azimuth 150 --elevation -30 --distance 0.3``), which
#: the env's ``render()`` takes by default.
RENDER_VIEW = CameraView(distance_m=0.3)


def check_size(width: int, height: int) -> None:
    """Refuse a picture side outside SIZE_RANGE pixels (or not an integer)."""
    for name, v in (("width", width), ("height", height)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) \
                or not SIZE_RANGE[0] <= v <= SIZE_RANGE[1]:
            raise ValueError(f"{name} = {v!r}: allowed {SIZE_RANGE[0]}-{SIZE_RANGE[1]} pixels")


def posed_data(model: mujoco.MjModel, qpos, mocap_pos, mocap_quat,
               data: mujoco.MjData | None = None) -> mujoco.MjData:
    """``data`` (default: a new one) at this state, after ``mj_forward`` (poses and contacts).

    Raises:
        ValueError: a state that does not fit the model.
    """
    if np.shape(qpos) != (model.nq,):
        raise ValueError(f"qpos has shape {np.shape(qpos)}; the model has nq = {model.nq}")
    if np.shape(mocap_pos) != (model.nmocap, 3) or np.shape(mocap_quat) != (model.nmocap, 4):
        raise ValueError(f"mocap poses have shapes {np.shape(mocap_pos)}, {np.shape(mocap_quat)};"
                         f" the model has nmocap = {model.nmocap}")
    data = mujoco.MjData(model) if data is None else data
    data.qpos[:] = qpos
    data.mocap_pos[:] = mocap_pos
    data.mocap_quat[:] = mocap_quat
    mujoco.mj_forward(model, data)
    return data


def hand_colours(model: mujoco.MjModel, prefixes: tuple[str, ...] = tuple(HAND_COLOURS)
                 ) -> dict[int, tuple[float, ...]]:
    """Geom id -> its hand's colour (HAND_COLOURS, by name prefix; ``prefixes``: of these hands
    only, e.g. the partner's where the prosthetic's skin is coloured by force); a hidden geom
    (alpha 0, e.g. the skin a flex pad replaces) stays hidden."""
    out = {}
    for g in range(model.ngeom):
        if model.geom_rgba[g, 3] == 0:
            continue
        for prefix in prefixes:
            if model.geom(g).name.startswith(prefix):
                out[g] = HAND_COLOURS[prefix]
    return out


class ScenePicture:
    """An offscreen renderer of ``model`` at ``width`` x ``height`` pixels, kept open between
    draws (the env keeps one; ``with ScenePicture(...) as p`` closes it after one picture)."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int) -> None:
        check_size(width, height)
        self.model, self.width, self.height = model, int(width), int(height)
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, self.width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, self.height)
        self._renderer: mujoco.Renderer | None = mujoco.Renderer(model, self.height, self.width)

    def draw(self, data: mujoco.MjData, view: CameraView | None = None, *,
             contacts: bool = True, colours: dict[int, tuple[float, ...]] | None = None
             ) -> np.ndarray:
        """Pixels (height, width, 3) uint8 of ``data`` seen from ``view`` (default RENDER_VIEW),
        the geoms in ``colours`` (default: hand_colours) recoloured for this picture only."""
        if self._renderer is None:
            raise RuntimeError("the picture's renderer is closed")
        model = self.model
        view = RENDER_VIEW if view is None else view
        colours = hand_colours(model) if colours is None else colours
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        cam.lookat[:] = (np.mean(data.xpos[1:], axis=0) if view.lookat is None
                         else np.asarray(view.lookat, dtype=float))
        cam.distance, cam.azimuth, cam.elevation = (view.distance_m, view.azimuth_deg,
                                                    view.elevation_deg)
        opt = mujoco.MjvOption()
        opt.flags[mujoco.mjtVisFlag.mjVIS_CONTACTPOINT] = contacts
        model.vis.scale.contactwidth = 0.05  # contact points as small discs (scaled by extent)
        model.vis.scale.contactheight = 0.01
        rgba = model.geom_rgba.copy()
        point = model.vis.rgba.contactpoint.copy()
        for g, colour in colours.items():
            model.geom_rgba[g] = colour
        model.vis.rgba.contactpoint[:] = CONTACT_COLOUR
        renderer = self._renderer
        try:
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

    def close(self) -> None:
        """Free the renderer and its OpenGL context (closing twice is harmless)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    @property
    def closed(self) -> bool:
        return self._renderer is None

    def __enter__(self) -> ScenePicture:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def force_colors(
    force_N: np.ndarray | float, *, max_force_N: float = 5.0, standout_N: float = STANDOUT_FORCE_N
) -> np.ndarray:
    """RGBA colours (uint8, shape ``force_N.shape + (4,)``) for normal forces.

    From 0 N to ``standout_N`` a grey ramp, pale to mid grey; above ``standout_N`` a warm ramp,
    orange to red at ``max_force_N`` and beyond, so that regions over 2 N stand out (no blue: blue
    is the partner's hand in every picture).

    Raises:
        ValueError: if ``max_force_N`` or ``standout_N`` is not a positive finite number.
    """
    for name, value in (("max_force_N", max_force_N), ("standout_N", standout_N)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} = {value}: expected a positive finite force in N")
    f = np.asarray(force_N, dtype=float)
    cool = np.clip(f / standout_N, 0.0, 1.0)[..., None]
    span = max_force_N - standout_N
    warm = (np.clip((f - standout_N) / span, 0.0, 1.0) if span > 0 else np.ones_like(f))[..., None]
    rgb = np.where(
        (f > standout_N)[..., None],
        _WARM[0] + warm * (_WARM[1] - _WARM[0]),
        _COOL[0] + cool * (_COOL[1] - _COOL[0]),
    )
    alpha = np.full(f.shape + (1,), 255.0)
    return np.round(np.concatenate([rgb, alpha], axis=-1)).astype(np.uint8)


def skin_forces(model: mujoco.MjModel, region_names, forces) -> dict[str, float]:
    """Skin geom name -> force (N) for `region_colours`, from each region's force: a skin that
    carries several regions as zones (the palm's surface) shows its largest."""
    info = regions(model) if len(region_names) else {}
    out: dict[str, float] = {}
    for region, f in zip(region_names, forces, strict=True):
        name = info[region].geom
        out[name] = max(out.get(name, float("-inf")), float(f))
    return out


def region_colours(model: mujoco.MjModel, region_force_N: dict[str, float]
                   ) -> dict[int, tuple[float, ...]]:
    """Geom colours of a picture by force (`ScenePicture.draw`'s ``colours``): each prosthetic
    skin region by its force (`force_colors`: pale to mid grey under 2 N, orange to red over),
    its other skin grey, the partner's tissue blue (HAND_COLOURS, as in every picture); a hidden
    geom (alpha 0: the skin a flex pad replaces) stays hidden. ``region_force_N``: skin geom
    name -> N."""
    colours = dict(hand_colours(model, ("hum_tissue_",)))
    for g in range(model.ngeom):
        name = model.geom(g).name
        if name.startswith("pro_skin_") and model.geom_rgba[g, 3] > 0.0:
            f = region_force_N.get(name)
            colours[g] = ((0.75, 0.75, 0.75, 0.9) if f is None
                          else tuple(force_colors(f) / 255.0))
    return colours
