"""Warnings that point at the user's code, not at softhand's or Gymnasium's.

A warning raised deep inside softhand (a skin pair built outside its calibrated timestep, an episode
whose contacts went beyond their laws' range) is about something the user did: it should name the
line of the user's code that built the env or called ``env.step()``, even through Gymnasium's
wrappers (``gymnasium.make`` adds ``OrderEnforcing`` and ``PassiveEnvChecker``). A fixed
``stacklevel`` cannot do that: the depth changes with every wrapper. `warn_at_caller` walks out
of the frames of softhand and Gymnasium and attributes the warning to the first frame outside
them (Python 3.12's ``skip_file_prefixes`` does the same; softhand supports 3.10).

This module imports nothing from the stages, so each of them may use it.
"""

from __future__ import annotations

import os
import sys
import warnings

__all__ = ["INTERNAL_PREFIXES", "caller_stacklevel", "warn_at_caller"]


def _package_dir(name: str) -> str | None:
    module = sys.modules.get(name)
    path = getattr(module, "__file__", None)
    if path is None:
        try:
            module = __import__(name)
        except ImportError:  # pragma: no cover - gymnasium is a dependency
            return None
        path = module.__file__
    return os.path.dirname(os.path.abspath(path)) + os.sep


#: Folders whose frames a warning skips: softhand's package and Gymnasium's (its wrappers).
INTERNAL_PREFIXES: tuple[str, ...] = tuple(p for p in (_package_dir("softhand"),
                                                       _package_dir("gymnasium")) if p)


def caller_stacklevel(prefixes: tuple[str, ...] = INTERNAL_PREFIXES) -> int:
    """The ``stacklevel`` that makes a ``warnings.warn`` called in the caller of this function point
    at the first frame outside ``prefixes`` (1: the caller itself, when no frame is outside)."""
    frame = sys._getframe(1)  # the function that will call warnings.warn: stacklevel 1
    level, found = 1, 1
    while frame is not None:
        if not os.path.abspath(frame.f_code.co_filename).startswith(prefixes):
            found = level
            break
        frame = frame.f_back
        level += 1
    return found


def warn_at_caller(message: str, category: type[Warning]) -> None:
    """``warnings.warn(message, category)`` attributed to the user's code: the first frame on the
    stack outside softhand and Gymnasium (`INTERNAL_PREFIXES`)."""
    # caller_stacklevel counts from this function; warnings.warn counts from here too
    warnings.warn(message, category, stacklevel=caller_stacklevel())
