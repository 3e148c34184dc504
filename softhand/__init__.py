"""softhand: lifelike prosthetic skins, from FE indentation to a MuJoCo handshake.

Stages (each imports only the ones before it; docs/architecture.md has the whole table):

1. `softhand.fem` - FE indentation of the paper's synthetic phalanges.
2. `softhand.laws` - force-displacement and relaxation laws fitted to the FE curves.
3. `softhand.skin`, 3b `softhand.sensors`, 3c `softhand.design` - the laws in MuJoCo, what
   embedded sensors read, the design search over pockets, layers and materials.
4. `softhand.hands` - the two hands and the handshake grasp, built with MjSpec.
5. `softhand.envs` - skins and sensors on the hands, the two-hand touch env, the handshake.
6. `softhand.viz` - rerun recordings, pictures and figures; `softhand.bench` above them all.

Importing softhand picks MuJoCo's OpenGL backend for offscreen pictures (``env.render()``,
``softhand render``) on a Linux machine without a display, as the command line does: EGL, else
OSMesa, unless ``MUJOCO_GL`` is set or mujoco was imported first (MuJoCo reads it on import).
"""

import os as _os
import sys as _sys

__version__ = "0.1.0"


def _default_gl() -> None:
    if (not _sys.platform.startswith("linux") or "MUJOCO_GL" in _os.environ
            or _os.environ.get("DISPLAY") or _os.environ.get("WAYLAND_DISPLAY")
            or "mujoco" in _sys.modules):
        return
    import ctypes.util

    for backend, library in (("egl", "EGL"), ("osmesa", "OSMesa")):
        if ctypes.util.find_library(library):
            _os.environ["MUJOCO_GL"] = backend
            return


_default_gl()
