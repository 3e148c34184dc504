"""Test session setup: softhand's caches (solved grasps, softhand.paths.cache_dir) go to a folder of
this session, shared by its subprocesses and its pytest-xdist workers and removed at its end, so
that a run neither reads nor fills the user's cache, and a grasp one worker solved is read back by
the other.

The suite runs on pytest-xdist's workers (pyproject.toml's addopts: one per core), each test
file on one worker (``--dist loadfile``: its module fixtures built once); the tests that build the
checkout into a virtual environment hold `checkout_build_lock` while pip builds it (pip writes
the checkout's own build folders)."""

from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

from softhand.paths import CACHE_ENV

#: the environment variable through which the session's cache folder reaches its workers
_SESSION_ENV = "SOFTHAND_TEST_SESSION_CACHE"
_OWNER = _SESSION_ENV not in os.environ  # the controller (or a run without workers)
if _OWNER:
    os.environ[_SESSION_ENV] = tempfile.mkdtemp(prefix="softhand-test-cache-")
_CACHE = os.environ[_SESSION_ENV]
os.environ[CACHE_ENV] = _CACHE


@contextmanager
def checkout_build_lock():
    """Held while pip builds the checkout (``pip wheel``, ``pip install -e``): pip writes its
    build folders and ``softhand.egg-info`` into the checkout, so two workers building at once
    would write over each other. A file lock in the session's cache folder (POSIX ``flock``;
    without fcntl, none: the suite then runs its build tests as it finds them)."""
    try:
        import fcntl
    except ImportError:  # Windows
        yield
        return
    with open(Path(_CACHE) / "checkout-build.lock", "w") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def pytest_sessionfinish(session, exitstatus):
    if _OWNER:
        shutil.rmtree(_CACHE, ignore_errors=True)


def sigint_default() -> None:
    """``preexec_fn`` of a child that a test interrupts: SIGINT at its default, so that Python
    installs its KeyboardInterrupt handler in the child even when this run's parent ignores
    SIGINT (nohup, ``trap '' INT``, background jobs, some CI runners), whose children inherit
    the ignoring disposition."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)


#: seconds a child interrupted by a test has to end
HANG_S = 60


def start_interruptible(args: list[str], **kw):
    """A child in a session of its own (so that SIGINT reaches its group alone, as Ctrl-C in a
    terminal does), SIGINT at its default (`sigint_default`), text pipes."""
    import subprocess

    return subprocess.Popen(args, start_new_session=True, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=sigint_default, **kw)


def interrupt_when(proc, stream, marker: str) -> tuple[str, str]:
    """Read ``stream`` of ``proc`` until ``marker`` appears, then SIGINT its group; return its
    stdout and stderr (what was read included)."""
    import signal

    seen = ""
    while marker not in seen:
        ch = stream.read(1)
        if not ch:
            break
        seen += ch
    assert marker in seen, f"{marker!r} never appeared: {seen[-500:]}"
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=HANG_S)
    return (seen + out, err) if stream is proc.stdout else (out, seen + err)
