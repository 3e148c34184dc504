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

from softhand.requirements import CHECKED as _CHECKED  # noqa: E402
from softhand.requirements import RequirementError as _RequirementError  # noqa: E402
from softhand.requirements import check as _check  # noqa: E402

# an older numpy, scipy, mujoco, rerun-sdk or gymnasium fails deep inside, naming no version (an
# AttributeError; "No module named 'rerun.chunk'"): refused here, in one line (versions are read
# from the packages' metadata; nothing is imported). The command line, which imports this
# package before its own error handling runs, says it as its one line and exits 1.
try:
    _check(*_CHECKED)
except _RequirementError as _exc:
    _argv0 = _sys.argv[0] if _sys.argv else ""
    if _os.path.basename(_argv0) == "softhand" or _argv0 == "-m":  # the console script, python -m
        print(f"error: {_exc}", file=_sys.stderr)
        raise SystemExit(1) from None
    raise
