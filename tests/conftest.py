"""Test session setup: softhand's caches (solved grasps, softhand.paths.cache_dir) go to a folder of
this session, shared by its subprocesses and removed at its end, so that a run neither reads nor
fills the user's cache."""

from __future__ import annotations

import os
import shutil
import tempfile

from softhand.paths import CACHE_ENV

_CACHE = tempfile.mkdtemp(prefix="softhand-test-cache-")
os.environ[CACHE_ENV] = _CACHE


def pytest_sessionfinish(session, exitstatus):
    shutil.rmtree(_CACHE, ignore_errors=True)


def sigint_default() -> None:
    """``preexec_fn`` of a child that a test interrupts: SIGINT at its default, so that Python
    installs its KeyboardInterrupt handler in the child even when this run's parent ignores
    SIGINT (nohup, ``trap '' INT``, background jobs, some CI runners), whose children inherit
    the ignoring disposition."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
