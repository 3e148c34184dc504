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
