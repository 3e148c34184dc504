"""Atomic file writing (a temp file in the target folder, then ``os.replace``), checks that a
path can be written before any work starts, and a block that Ctrl-C cannot cut in half.

An interrupted run leaves either the old file or the new one, never a partial file.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

__all__ = ["atomic_open", "atomic_write_json", "atomic_write_text", "check_writable_dir",
           "check_writable_file", "interrupts_deferred"]


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "w") -> Iterator[IO]:
    """Open a temp file next to ``path``; on success rename it onto ``path``, else delete it."""
    if mode not in ("w", "wb"):
        raise ValueError(f"mode = {mode!r}: allowed 'w' or 'wb'")
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, mode, **({"encoding": "utf-8"} if mode == "w" else {})) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file normal permissions
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    with atomic_open(path, "w") as fh:
        fh.write(text)


def atomic_write_json(path: str | os.PathLike, data: Any) -> None:
    """Write ``data`` as indented JSON to ``path`` atomically."""
    atomic_write_text(path, json.dumps(data, indent=2, sort_keys=False) + "\n")


def _nearest_existing(path: Path) -> Path:
    p = path
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def check_writable_dir(path: str | os.PathLike, *, name: str = "path") -> Path:
    """``path`` as a folder that can be written (created with its parents if missing).

    Checked without writing anything: the path is not empty, is not a file, and it (or the
    nearest folder above it that exists) is a writable folder.

    Raises:
        ValueError: naming ``name`` and the path.
    """
    text = os.fspath(path)
    if not text.strip():
        raise ValueError(f"{name} = {text!r}: expected a folder path, got an empty string")
    target = Path(text)
    if target.exists() and not target.is_dir():
        raise ValueError(f"{name} = {text!r} is a file, not a folder")
    base = _nearest_existing(target.resolve())
    if not base.is_dir():
        raise ValueError(f"{name} = {text!r}: {str(base)!r} is a file, so no folder can be made "
                         "below it")
    if not os.access(base, os.W_OK | os.X_OK):
        raise ValueError(f"{name} = {text!r}: folder {str(base)!r} is not writable")
    return target


def check_writable_file(path: str | os.PathLike, *, suffix: str | None = None,
                        name: str = "path") -> Path:
    """``path`` as a file that can be written: right suffix, not a folder, writable folder.

    A missing folder is allowed when it can be created (see :func:`check_writable_dir`).

    Raises:
        ValueError: naming ``name``, the path and the expected suffix.
    """
    text = os.fspath(path)
    if not text.strip():
        raise ValueError(f"{name} = {text!r}: expected a file path, got an empty string")
    target = Path(text)
    if suffix is not None and target.suffix != suffix:
        raise ValueError(f"{name} = {text!r}: expected a file name ending in {suffix}")
    if target.is_dir():
        raise ValueError(f"{name} = {text!r} is a folder, not a file")
    if target.exists() and not os.access(target, os.W_OK):
        raise ValueError(f"{name} = {text!r}: the file is not writable")
    check_writable_dir(target.parent if str(target.parent) else ".", name=name)
    return target


@contextlib.contextmanager
def interrupts_deferred() -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) until the block ends, then raise it: files written together stay
    consistent. Outside the main thread the block runs as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if caught:
        raise KeyboardInterrupt
