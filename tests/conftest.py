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
