"""Atomic file writing (a temp file in the target folder, then ``os.replace``), checks that a
path can be written before any work starts (and that its disk has room), a folder written beside
its target and swapped in only when complete, JSON input files read with one clear error, and a
block that Ctrl-C cannot cut in half.

An interrupted run leaves either the old file or the new one, never a partial file; a staged
folder (`staged_folder`) leaves either the old set or the new complete set.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

__all__ = ["DeferredInterrupt", "Staged", "StaleStageWarning", "atomic_open", "atomic_write_json",
           "atomic_write_text", "check_free_space", "check_writable_dir", "check_writable_file",
           "interrupts_deferred", "read_json", "remove_stale_stages", "staged_folder"]

#: Longest file or folder name (bytes) and path that Linux and macOS file systems take
NAME_MAX, PATH_MAX = 255, 4096


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


def check_writable_dir(path: str | os.PathLike, *, name: str = "path",
                       shown: str | None = None) -> Path:
    """``path`` as a folder that can be written (created with its parents if missing).

    Checked before any work, leaving nothing behind: the path is not empty, no name in it is
    longer than the file system takes, it is not a file, and the nearest folder of it (or above
    it) that exists takes a new file: a probe file is made and removed there, so that a
    read-only mount or a folder that only looks writable (``os.access`` says yes to root
    everywhere) is found now, not after the work.

    Raises:
        ValueError: naming ``name`` and the path (or ``shown``: the file the folder is for).
    """
    text = os.fspath(path)
    if not text.strip():
        raise ValueError(f"{name} = {text!r}: expected a folder path, got an empty string")
    shown = shown or text
    shown = shown if len(shown) <= 80 else f"{shown[:40]}...{shown[-30:]}"
    long = [part for part in Path(text).parts if len(os.fsencode(part)) > NAME_MAX]
    if long or len(os.fsencode(text)) > PATH_MAX:
        what = (f"the name {long[0][:30]!r}... has {len(os.fsencode(long[0]))} bytes" if long
                else f"the path has {len(os.fsencode(text))} bytes")
        raise ValueError(f"{name} = {shown!r}: {what}; allowed at most {NAME_MAX} bytes a name "
                         f"and {PATH_MAX} a path")
    target = Path(text)
    if target.exists() and not target.is_dir():
        raise ValueError(f"{name} = {shown!r} is a file, not a folder" if shown == text else
                         f"{name} = {shown!r}: {text!r} is a file, not a folder")
    base = _nearest_existing(target.resolve())
    if not base.is_dir():
        raise ValueError(f"{name} = {shown!r}: {str(base)!r} is a file, so no folder can be made "
                         "below it")
    try:
        fd, probe = tempfile.mkstemp(prefix=".softhand-probe-", dir=base)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise ValueError(f"{name} = {shown!r}: folder {str(base)!r} is not writable "
                         f"({exc.strerror or exc})") from None
    return target


#: bytes the temporary file of `atomic_open` adds to a file's name: "." + "." + 8 + ".tmp"
_TEMP_NAME_EXTRA = 14


def check_writable_file(path: str | os.PathLike, *, suffix: str | None = None,
                        name: str = "path") -> Path:
    """``path`` as a file that can be written: right suffix, not a folder, writable folder.

    A missing folder is allowed when it can be created (see `check_writable_dir`).

    Raises:
        ValueError: naming ``name``, the path and the expected suffix.
    """
    text = os.fspath(path)
    if not text.strip():
        raise ValueError(f"{name} = {text!r}: expected a file path, got an empty string")
    target = Path(text)
    if suffix is not None and target.suffix != suffix:
        raise ValueError(f"{name} = {text!r}: expected a file name ending in {suffix}")
    # atomic writes go through a temporary ".{name}.XXXXXXXX.tmp" beside it (`atomic_open`)
    base = _nearest_existing(Path(os.path.abspath(target.parent if str(target.parent) else ".")))
    try:
        name_max = os.pathconf(base if base.is_dir() else base.parent, "PC_NAME_MAX")
    except (OSError, ValueError):
        name_max = 255
    limit = name_max - _TEMP_NAME_EXTRA
    if len(target.name.encode()) > limit:
        raise ValueError(f"{name} = {text!r}: the file name is {len(target.name.encode())} bytes "
                         f"long; allowed at most {limit} (the file system's {name_max} less "
                         f"{_TEMP_NAME_EXTRA} for the temporary name it is written through)")
    if target.is_dir():
        raise ValueError(f"{name} = {text!r} is a folder, not a file")
    if target.exists() and not target.is_file():
        raise ValueError(f"{name} = {text!r} is not a regular file (a device, a pipe or a "
                         "socket): expected a file path")
    if target.exists() and not os.access(target, os.W_OK):
        raise ValueError(f"{name} = {text!r}: the file is not writable")
    check_writable_dir(target.parent if str(target.parent) else ".", name=name, shown=text)
    return target


def check_free_space(path: str | os.PathLike, need_bytes: float, *, name: str = "path") -> None:
    """Refuse when the disk that would hold ``path`` has less than ``need_bytes`` free.

    ``need_bytes`` is the caller's estimate of what the run writes (a recording, a sweep's
    curves), checked before the work so that a full disk is found in a second, not at the end.

    Raises:
        ValueError: naming ``name``, the path, the bytes needed and the bytes free.
    """
    base = _nearest_existing(Path(os.fspath(path)).resolve())
    free = shutil.disk_usage(base if base.is_dir() else base.parent).free
    if free < need_bytes:
        raise ValueError(f"{name} = {os.fspath(path)!r}: this run writes about "
                         f"{_size(need_bytes)} and the disk of {str(base)!r} has "
                         f"{_size(free)} free")


def _size(n: float) -> str:
    for unit in ("B", "kB", "MB", "GB"):
        if n < 1000 or unit == "GB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000
    raise AssertionError  # pragma: no cover


def read_json(path: str | os.PathLike, *, name: str | None = None) -> Any:
    """The JSON document of a regular file; every failure is one ValueError naming the file.

    Not a regular file (``/dev/zero``, a folder, a pipe: reading them hangs or fails late),
    unreadable, not UTF-8, not JSON, or nested past what the parser takes are refused. NaN and
    Infinity parse (as Python's parser reads them) so that the file's validator names the key
    that holds them.
    """
    target = Path(os.fspath(path))
    label = name or str(target)
    if not target.exists():
        raise ValueError(f"{label}: no such file")
    if not target.is_file():
        raise ValueError(f"{label}: not a regular file (a folder, device or pipe)")
    try:
        return json.loads(target.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"{label}: cannot be read ({exc.__class__.__name__}: {exc})") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{label}: not JSON (line {exc.lineno}, column {exc.colno}: "
                         f"{exc.msg})") from None
    except RecursionError:
        raise ValueError(f"{label}: nested too deeply to be a softhand file") from None


class Staged:
    """A folder to write a set into (see `staged_folder`)."""

    def __init__(self, target: Path, path: Path) -> None:
        self.target, self.path, self.committed = target, path, False

    def commit(self) -> None:
        """Put the written set in place of the target (two renames, Ctrl-C held meanwhile)."""
        if self.path == self.target:
            self.committed = True
            return
        with interrupts_deferred():
            old = None
            if self.target.exists():
                old = Path(tempfile.mkdtemp(prefix=f".{self.target.name}.old-",
                                            dir=self.target.parent))
                (old / _OWNER).write_text(str(os.getpid()), encoding="utf-8")
                os.rename(self.target, old / self.target.name)
            os.rename(self.path, self.target)
            self.committed = True
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)


#: the file in a staging folder that names the process writing it
_OWNER = "owner.pid"


class StaleStageWarning(UserWarning):
    """A staging folder left beside a set by a run that was killed (kill -9, a power cut) was
    removed by the next run that writes there."""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process: alive
        return True
    return True


def remove_stale_stages(target: str | os.PathLike) -> list[Path]:
    """Remove the staging folders ``.{name}.new-*`` and ``.{name}.old-*`` beside ``target`` that
    no live process owns (a run killed before it could clean up: `staged_folder` removes its
    own otherwise), each with a `StaleStageWarning`; return them. A folder whose owner still
    runs (a concurrent run writing there) is left alone; an ``old`` one that holds the set
    while ``target`` is missing (a run killed between a commit's two renames) gives it back
    first."""
    import warnings

    target = Path(os.fspath(target))
    removed = []
    if not target.parent.is_dir():
        return removed
    for kind in ("new", "old"):
        for stage in sorted(target.parent.glob(f".{target.name}.{kind}-*")):
            if not stage.is_dir():
                continue
            try:
                pid = int((stage / _OWNER).read_text(encoding="utf-8").strip())
            except (OSError, ValueError):
                pid = None
            if pid is not None and pid != os.getpid() and _alive(pid):
                continue
            if pid is None and time.time() - stage.stat().st_mtime < 60.0:
                continue  # being made this moment: its owner writes owner.pid next
            if kind == "old" and not target.exists() and (stage / target.name).is_dir():
                # killed between the two renames of a commit: the earlier set is put back
                os.rename(stage / target.name, target)
                warnings.warn(f"put back {target} from {stage}, where a run killed while it "
                              "swapped in its new set had left it", StaleStageWarning,
                              stacklevel=2)
            shutil.rmtree(stage, ignore_errors=True)
            removed.append(stage)
            warnings.warn(f"removed {stage}, a staging folder of {target.name} that an earlier "
                          "run left when it was killed", StaleStageWarning, stacklevel=2)
    return removed


@contextlib.contextmanager
def staged_folder(target: str | os.PathLike, *, stage: bool) -> Iterator[Staged]:
    """A folder to write a whole set into, swapped in for ``target`` only on `Staged.commit`.

    With ``stage`` (shipped data), the set is written into a copy of ``target`` made beside it;
    ``commit()`` swaps the copy in; leaving the block without a commit (Ctrl-C, a failed design,
    a disk that filled up) deletes the copy, so ``target`` keeps its old complete set byte for
    byte. Without ``stage``, the block writes into ``target`` itself (what finished is kept).
    """
    target = Path(os.fspath(target))
    if not stage:
        target.mkdir(parents=True, exist_ok=True)
        yield Staged(target, target)
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_stages(target)
    holder = Path(tempfile.mkdtemp(prefix=f".{target.name}.new-", dir=target.parent))
    (holder / _OWNER).write_text(str(os.getpid()), encoding="utf-8")
    path = holder / target.name
    try:
        if target.exists():
            shutil.copytree(target, path, symlinks=True)
        else:
            path.mkdir()
        staged = Staged(target, path)
        yield staged
    finally:
        shutil.rmtree(holder, ignore_errors=True)


class DeferredInterrupt(KeyboardInterrupt):
    """A Ctrl-C held by `interrupts_deferred` until its block had finished: what the block
    wrote is complete (the command line says so, instead of "nothing was written")."""


@contextlib.contextmanager
def interrupts_deferred() -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) until the block ends, then raise it (`DeferredInterrupt`): files
    written together stay consistent. Outside the main thread the block runs as it is."""
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
        raise DeferredInterrupt
