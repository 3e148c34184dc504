"""Offscreen pictures of the handshake scene (``mujoco.Renderer``), written as PNG.

:func:`render_state` draws one state of the scene (both hands and MuJoCo's contact points) from a
free camera around the hands. The caller hands the state over as plain arrays (``qpos`` and the
mocap poses), as for the rerun recording, so this stage does not import the environment.

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

__all__ = ["HAND_COLOURS", "CameraView", "render_state"]

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
                 contacts: bool = True) -> Path:
    """Render one state of the scene to a PNG at ``path`` (written atomically); return the path.

    Raises:
        ValueError: a state that does not fit the model, a size outside [64, 4096] pixels or a
            path that is not a writable ``.png``.
    """
    target = check_writable_file(path, suffix=".png")
    if np.shape(qpos) != (model.nq,):
        raise ValueError(f"qpos has shape {np.shape(qpos)}; the model has nq = {model.nq}")
    if np.shape(mocap_pos) != (model.nmocap, 3) or np.shape(mocap_quat) != (model.nmocap, 4):
        raise ValueError(f"mocap poses have shapes {np.shape(mocap_pos)}, {np.shape(mocap_quat)};"
                         f" the model has nmocap = {model.nmocap}")
    for name, v in (("width", width), ("height", height)):
        if not 64 <= v <= 4096:
            raise ValueError(f"{name} = {v!r}: allowed 64-4096 pixels")
    view = view or CameraView()
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    data.mocap_pos[:] = mocap_pos
    data.mocap_quat[:] = mocap_quat
    mujoco.mj_forward(model, data)
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
    # two hands, two colours: the prosthetic's skin warm, the partner's tissue blue
    rgba = model.geom_rgba.copy()
    for g in range(model.ngeom):
        name = model.geom(g).name
        for prefix, colour in HAND_COLOURS.items():
            if name.startswith(prefix):
                model.geom_rgba[g] = colour
    try:
        with mujoco.Renderer(model, height, width) as renderer:
            renderer.update_scene(data, camera=cam, scene_option=opt)
            pixels = renderer.render()
    finally:
        model.geom_rgba[:] = rgba
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with atomic_open(target, "wb") as fh:
        plt.imsave(fh, pixels, format="png")
    return target
