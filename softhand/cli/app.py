"""The ``softhand`` command group: errors as one line and exit statuses (`softhand.cli`), Ctrl-C
and SIGTERM, warnings summarised once, and the write blocks shared by the commands that write
batches."""

from __future__ import annotations

import errno
import os
import signal
import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import NoReturn

import click

from softhand import __version__
from softhand.cli.inputs import (
    EXIT_INPUT,
    bad,
)
from softhand.io import DeferredInterrupt
from softhand.paths import is_shipped

EXIT_CONVERGENCE, EXIT_WRITE, EXIT_INTERRUPTED = 3, 4, 130


class Stopped(click.ClickException):
    """Work that ended early (interrupted, not converged) after writing what finished."""

    def __init__(self, message: str, exit_code: int) -> None:
        super().__init__(message)
        self.exit_code = exit_code


class _Softhand(click.Group):
    """The top-level group: errors become one line on stderr, never a traceback."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        try:
            with _warnings_summarised():  # each kind once, with its count, at the end
                rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.exceptions.NoArgsIsHelpError as exc:
            click.echo(exc.format_message())
            sys.exit(0)
        except click.UsageError as exc:  # bad flag or value: name it, point at --help
            hint = f" (see '{exc.ctx.command_path} --help')" if exc.ctx else ""
            click.echo(f"error: {exc.format_message()}{hint}", err=True)
            sys.exit(EXIT_INPUT)
        except click.ClickException as exc:
            click.echo(("" if isinstance(exc, Stopped) else "error: ") + exc.format_message(),
                       err=True)
            sys.exit(exc.exit_code)
        except (click.Abort, KeyboardInterrupt) as exc:
            # click turns a KeyboardInterrupt into Abort, from it
            _interrupted(written=isinstance(exc.__cause__ or exc, DeferredInterrupt))
        except Exception as exc:
            if _caused_by_interrupt(exc):  # e.g. Ctrl-C during a lazy import, wrapped by it
                _interrupted()
            if os.environ.get("SOFTHAND_TRACEBACK"):
                raise
            if isinstance(exc, OSError) and exc.errno in _WRITE_ERRNOS:
                where = f" {exc.filename}" if exc.filename else ""
                click.echo(f"error: could not write{where} ({exc.strerror}); the files written "
                           "before it are kept, each whole (atomic writes)", err=True)
                sys.exit(EXIT_WRITE)
            click.echo(f"internal error: {type(exc).__name__}: {exc} "
                       "(SOFTHAND_TRACEBACK=1 shows where)", err=True)
            sys.exit(1)
        sys.exit(rv if isinstance(rv, int) else 0)


#: A write that failed for the disk or the file system, not for a bug: exit 4, one line
_WRITE_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG, errno.EACCES, errno.EPERM}


def _caused_by_interrupt(exc: BaseException) -> bool:
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def _interrupted(written: bool = False) -> NoReturn:
    """Ctrl-C: one line, exit 130; a second Ctrl-C while exiting is ignored. ``written``: the
    Ctrl-C came while the results that had finished were being written, and was held until they
    were (softhand.io.interrupts_deferred)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    click.echo(f"interrupted ({_STOP['by']}) while writing: what had finished was written, each "
               "file whole" if written else f"interrupted ({_STOP['by']}); nothing was written",
               err=True)
    sys.stdout.flush()
    sys.exit(EXIT_INTERRUPTED)


@click.group(cls=_Softhand)
@click.version_option(__version__, prog_name="softhand")
def main() -> None:
    """softhand: lifelike prosthetic skins, from FE indentation to MuJoCo."""
    warnings.formatwarning = _one_line_warning
    signal.signal(signal.SIGTERM, _terminated)


#: What stopped the command: Ctrl-C, or SIGTERM (a ``kill``, a scheduler's time limit).
_STOP = {"by": "Ctrl-C"}


def _terminated(signum, frame) -> NoReturn:
    """SIGTERM takes Ctrl-C's path: a batch terminates its workers and writes what finished (the
    default action killed this process alone and left the spawned workers running as orphans)."""
    _STOP["by"] = "SIGTERM"
    raise KeyboardInterrupt


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    """A warning as the command line shows it: one line, its class and message, no source."""
    return f"warning ({category.__name__}): {message}\n"


@contextmanager
def _warnings_summarised() -> Iterator[None]:
    """Collect the command's warnings (under the filters in force: ``-W`` and
    ``PYTHONWARNINGS`` still apply, ``error`` included) and print each kind once when it ends,
    however it ends: ``warning (Kind): message``, or ``warning (Kind) xN: first message (and N-1
    more like it)``. Warnings from worker processes come back to this process
    (softhand.parallel.run_tasks) and are counted here too."""
    with warnings.catch_warnings(record=True) as caught:
        try:
            yield
        finally:
            kinds: dict[str, list[str]] = {}
            for w in caught:
                kinds.setdefault(w.category.__name__, []).append(str(w.message))
            for name, texts in kinds.items():  # _one_line_warning's format, with the count
                n = len(texts)
                more = f" (and {n - 1} more like it)" if n > 1 else ""
                click.echo(f"warning ({name}){f' x{n}' if n > 1 else ''}: {texts[0]}{more}",
                           err=True)


@contextmanager
def _writing(out: Path, kept: str) -> Iterator[None]:
    """Turn a failure to write (disk full, permissions changed) into one line saying what was
    kept, exit 4."""
    try:
        yield
    except OSError as exc:
        what = f"{exc.strerror or exc}" + (f": {exc.filename}" if exc.filename else "")
        kept = ("the shipped data is unchanged" if is_shipped(out) else f"kept in {out}: {kept}")
        raise Stopped(f"error: writing into {out} failed ({what}); {kept}", EXIT_WRITE) from None


def _end_of_batch(what: str, written: int, total: int, out: Path, missing: dict[str, str],
                  interrupted: bool, *, staged: bool = False, beside: list[Path] = ()) -> None:
    """One closing line for a batch that did not finish whole (exit 130 or 3); else nothing.

    ``staged``: the run wrote shipped data beside it, so the incomplete set was dropped;
    ``beside``: the folders where an incomplete set went because its folder held an earlier
    set, which it does not replace."""
    where = (f"the shipped set in {out} is unchanged (an incomplete run never replaces it; the "
             f"{written} finished {what} were dropped: --out DIR keeps them)" if staged
             else f"wrote {written} of {total} {what} to {out}")
    if beside:
        where += (f" (the earlier complete set{'s' if len(beside) > 1 else ''} kept, an "
                  "incomplete run never replaces one: the finished ones are in "
                  + ", ".join(str(b) for b in beside) + ")")
    if interrupted:
        raise Stopped(f"interrupted ({_STOP['by']}): {where}; missing: {', '.join(missing)}",
                      EXIT_INTERRUPTED)
    if missing:
        reasons = "; ".join(f"{n}: {why}" for n, why in missing.items())
        raise Stopped(f"error: {len(missing)} {what} failed ({reasons}); {where}",
                      EXIT_CONVERGENCE)


def _folder_bytes(path: str | Path) -> int:
    """Bytes of the files under ``path`` (what a staged copy of it takes)."""
    root = Path(path)
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file()) if root.is_dir() else 0


def _check_gl() -> None:
    """MUJOCO_GL names a backend MuJoCo has, and this machine can open it (a wrong or missing one
    fails deep inside the first render, after the simulation): the backend's library is
    installed (libEGL, libOSMesa), and glfw has a display to open a window on."""
    import ctypes.util
    import sys

    value = os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported
    if value not in ("egl", "osmesa", "glfw"):
        bad(f"MUJOCO_GL = {value!r}: allowed egl (GPU, headless), osmesa (CPU, headless) or "
            "glfw (a window system)")
    if not sys.platform.startswith("linux"):
        return
    library = {"egl": "EGL", "osmesa": "OSMesa"}.get(value)
    if library is not None and ctypes.util.find_library(library) is None:
        other = [b for b, lib in (("egl", "EGL"), ("osmesa", "OSMesa"))
                 if b != value and ctypes.util.find_library(lib)]
        bad(f"MUJOCO_GL = {value!r}: lib{library} is not installed on this machine; "
            + (f"MUJOCO_GL={other[0]} works here" if other else
               "install libEGL (GPU) or libOSMesa (CPU) for offscreen pictures"))
    if value == "glfw" and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        bad("MUJOCO_GL = 'glfw': glfw opens a window and there is no display here (DISPLAY is "
            "unset); MUJOCO_GL=egl or osmesa render offscreen")


def run() -> None:
    """The ``softhand`` console script: `main`, and an exit 130 that stays 130.

    CPython exits by SIGINT (status -2) after a handled Ctrl-C when the interrupt first surfaced
    inside code that C evaluated with ``PyRun_*`` (a Cython module being imported, for one), even
    though the program then exits with its own status. So after Ctrl-C the process flushes its
    output, runs the exit handlers and ends with ``os._exit(130)``; what had to be written is
    closed by then.
    """
    try:
        main()
    except SystemExit as exc:
        if exc.code == EXIT_INTERRUPTED:
            import atexit

            atexit._run_exitfuncs()  # what a normal exit runs (e.g. multiprocessing's clean-up)
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(EXIT_INTERRUPTED)
        raise
