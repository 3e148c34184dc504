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

from dataclasses import dataclass

import mujoco
import numpy as np

__all__ = ["BACKGROUND", "CONTACT_COLOUR", "HAND_COLOURS", "RENDER_VIEW", "CameraView",
           "ScenePicture", "check_size", "hand_colours", "posed_data"]

#: Background of every picture (RGB, 0-255): light, so that pictures print and read in documents.
BACKGROUND = (244, 244, 240)
#: Colour of MuJoCo's contact-point markers in a picture (RGBA, 0-1): dark magenta on any skin.
CONTACT_COLOUR = (0.75, 0.0, 0.55, 1.0)
#: Colour of each hand's soft geoms in a picture (by name prefix): prosthetic skin, partner tissue.
HAND_COLOURS = {"pro_skin_": (0.95, 0.62, 0.32, 0.85), "hum_tissue_": (0.25, 0.5, 0.9, 0.8)}
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
