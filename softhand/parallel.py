"""Parallelism with one owner per process, and batches of work that stop cleanly on Ctrl-C.

softhand uses the cores at one level at a time, never two levels at once:

* one FE run: ``threads`` threads evaluate element blocks (:mod:`softhand.fem.assembly`); BLAS is
  held at one thread for the whole run (:func:`single_threaded_blas`), because OpenBLAS threads
  busy-wait between calls and, on top of the element threads, take cores that other work needs;
* a batch (FE sweep, calibration): ``threads`` worker processes, one task each at a time, each
  single-threaded (element threads and BLAS).

The default (:func:`default_threads`) is the number of CPUs this process may run on (its affinity
mask, which respects ``taskset`` and container limits), at most :data:`MAX_THREADS`.

:func:`run_tasks` runs a batch. Ctrl-C (SIGINT to the process group) reaches the main process only:
workers ignore it, the main process terminates them at once, and the tasks that had finished are
returned with the list of those that did not, so the caller can write what finished.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import pickle
import signal
import warnings
from collections.abc import Callable, Hashable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

__all__ = ["MAX_THREADS", "BatchOutcome", "TaskError", "available_cpus", "check_threads",
           "default_threads", "run_tasks", "single_threaded_blas"]

MAX_THREADS = 4  # element blocks: 2 threads take 0.6x the time of one, more gain little


def available_cpus() -> int:
    """CPUs this process may run on (affinity mask where the OS has one, else the CPU count)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # pragma: no cover - macOS, Windows
        return max(1, os.cpu_count() or 1)


def default_threads() -> int:
    """The default ``--threads``: available CPUs, at most :data:`MAX_THREADS`."""
    return min(MAX_THREADS, available_cpus())


def check_threads(threads: int | None, *, name: str = "threads") -> int:
    """``threads`` as an int >= 1 (None: :func:`default_threads`).

    Raises:
        ValueError: not an integer >= 1.
    """
    if threads is None:
        return default_threads()
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"{name} = {threads!r}: allowed an integer >= 1")
    return threads


@contextlib.contextmanager
def single_threaded_blas() -> Iterator[None]:
    """Hold BLAS/OpenMP thread pools at one thread inside the block (threadpoolctl)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        yield


class TaskError(RuntimeError):
    """A task failed in a worker; ``kind`` is the original exception's class name."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(f"{kind}: {message}")
        self.kind = kind
        self.message = message


@dataclass(frozen=True)
class BatchOutcome:
    """What a batch produced.

    Attributes:
        results: finished tasks, in the order of the input.
        errors: failed tasks and why (:class:`TaskError` from workers, the exception in-process).
        missing: tasks that neither finished nor failed (interrupted), in input order.
        interrupted: True when Ctrl-C stopped the batch.
    """

    results: dict[Hashable, Any]
    errors: dict[Hashable, BaseException] = field(default_factory=dict)
    missing: list[Hashable] = field(default_factory=list)
    interrupted: bool = False

    @property
    def complete(self) -> bool:
        return not self.errors and not self.missing


def _init_worker() -> None:
    """Worker start-up: Ctrl-C is the main process's to handle; one BLAS thread."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)


def _call(job: tuple[Callable, Hashable, tuple]) -> tuple[Hashable, bool, Any, list[tuple]]:
    """Run one task in a worker; its warnings (under the worker's filters) go back with it."""
    fn, key, args = job
    with warnings.catch_warnings(record=True) as caught:
        try:
            out = key, True, fn(*args)
        except Exception as exc:  # sent back as text: not every exception pickles
            out = key, False, (type(exc).__name__, str(exc))
    return (*out, [_portable(w) for w in caught])


def _portable(w: warnings.WarningMessage) -> tuple[type[Warning], str, str, int]:
    """A recorded warning as (category, text, filename, line) that pickles: a category that does
    not pickle by reference (defined in a function) travels as UserWarning, its name in the text."""
    text, category = str(w.message), w.category
    try:
        pickle.dumps(category)
    except Exception:
        text, category = f"{category.__name__}: {text}", UserWarning
    return category, text, w.filename, w.lineno


def _reissue(caught: list[tuple], registry: dict) -> None:
    """Raise a worker's warnings again in this process, at their own file and line, under this
    process's filters; ``registry`` is the batch's, so that the same warning from several workers
    shows once under the ``default`` action, as it would from one process."""
    for category, text, filename, lineno in caught:
        warnings.warn_explicit(text, category, filename, lineno, registry=registry)


def run_tasks(fn: Callable[..., Any], tasks: Sequence[tuple[Hashable, tuple]], *,
              threads: int | None = None,
              on_done: Callable[[Hashable, bool], None] | None = None) -> BatchOutcome:
    """Run ``fn(*args)`` for every ``(key, args)`` of ``tasks``; stop cleanly on Ctrl-C.

    Args:
        fn: a module-level function (it is sent to spawned worker processes).
        tasks: (key, args) pairs; keys are unique. They start in this order.
        threads: worker processes (None: :func:`default_threads`); 1 runs in this process (BLAS
            single-threaded, Ctrl-C interrupts the running task).
        on_done: called in the main process with (key, succeeded) after each task.

    Warnings raised by a task in a worker are sent back with its result and raised again in
    this process (at their own file and line, under this process's filters, each distinct one
    once per batch under the ``default`` action), so that the caller sees and may record them as
    if the task had run here.

    Returns:
        The outcome; a failed task does not stop the others.
    """
    jobs = min(len(tasks), check_threads(threads)) or 1
    results: dict[Hashable, Any] = {}
    errors: dict[Hashable, BaseException] = {}
    interrupted = False
    if jobs == 1:
        try:
            with single_threaded_blas():
                for key, args in tasks:
                    try:
                        results[key] = fn(*args)
                    except Exception as exc:
                        errors[key] = exc
                    if on_done:
                        on_done(key, key in results)
        except KeyboardInterrupt:
            interrupted = True
    else:
        pool = None
        registry: dict = {}  # the batch's record of warnings shown (_reissue)
        try:
            pool = multiprocessing.get_context("spawn").Pool(jobs, initializer=_init_worker)
            for key, ok, value, caught in pool.imap_unordered(
                    _call, [(fn, key, args) for key, args in tasks], chunksize=1):
                _reissue(caught, registry)
                if ok:
                    results[key] = value
                else:
                    errors[key] = TaskError(*value)
                if on_done:
                    on_done(key, ok)
            pool.close()
        except KeyboardInterrupt:
            interrupted = True
        finally:
            if pool is not None:
                pool.terminate()
                pool.join()
    order = [key for key, _ in tasks]
    return BatchOutcome(results={k: results[k] for k in order if k in results}, errors=errors,
                        missing=[k for k in order if k not in results and k not in errors],
                        interrupted=interrupted)
