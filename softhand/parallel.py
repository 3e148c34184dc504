"""Parallelism with one owner per process, and batches of work that stop cleanly on Ctrl-C.

softhand uses the cores at one level at a time, never two levels at once:

* one FE run: ``threads`` threads evaluate element blocks (`softhand.fem.assembly`); BLAS is
  held at one thread for the whole run (`single_threaded_blas`), because OpenBLAS threads
  busy-wait between calls and, on top of the element threads, take cores that other work needs;
* a batch (FE sweep, calibration, population): ``threads`` worker processes, one task each at a
  time, each single-threaded (element threads and BLAS).

The default (`default_threads`) is the number of CPUs this process may run on (its affinity
mask, which respects ``taskset`` and container limits), at most `MAX_THREADS`.

`run_tasks` runs a batch, on joblib's loky worker processes by default (nothing to set
up), or on a Dask distributed cluster when given its scheduler's address (``cluster``, the
command line's ``--cluster tcp://HOST:PORT``; ``pip install 'softhand[cluster]'``). Either way:

* the outcome is a `BatchOutcome`: results in the order of the input, a task that raised
  is a `TaskError` (its class name and message) and does not stop the others;
* tasks start in the order given; ``on_done`` runs in this process after each task, as it ends;
* the warnings a task raised come back with its result and are raised again here, each distinct
  one once per batch;
* Ctrl-C (SIGINT to the process group) reaches the main process only: local workers ignore it
  and are terminated at once; the tasks that had finished are returned with the list of those
  that did not (``missing``), so that the caller can write what finished (atomically);
* workers are single-threaded (BLAS, OpenMP) and run one task at a time.

Local workers are started for one batch and stopped after it (joblib keeps them for the next
batch by default): a batch sees the caller's ``sys.path`` and modules as they are, and no idle
worker outlives it. A local worker process that dies (killed, out of memory) stops the batch:
the tasks not finished by then fail with a `TaskError` saying so (the spawn pool this
replaces waited for ever).

The cluster's address is checked before any task (`check_cluster`): its form, then a
scheduler answering within `CLUSTER_TIMEOUT_S`; each refusal is one ``ValueError`` naming
the value and what is allowed. ``threads`` and ``cluster`` exclude each other: the cluster's
workers set how many tasks run at once. Each task is one Dask future, so that progress is per
task; a worker that dies has its task rerun elsewhere by Dask (``KilledWorker`` after a few).
On a cluster, a Ctrl-C cancels the batch's tasks; a task already running on a remote worker
cannot be stopped from here (Dask runs it in a thread) and runs to its end, its result dropped.
Cluster workers need softhand installed (the same version) and one thread each
(``dask worker ADDRESS --nthreads 1``): warnings are recorded per process.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import threading
import uuid
import warnings
from collections.abc import Callable, Hashable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import urlsplit

__all__ = ["CLUSTER_TIMEOUT_S", "MAX_THREADS", "BatchOutcome", "TaskError", "available_cpus",
           "check_cluster", "check_threads", "default_threads", "run_tasks",
           "single_threaded_blas"]

MAX_THREADS = 4  # element blocks: 2 threads take 0.6x the time of one, more gain little
CLUSTER_TIMEOUT_S = 5.0  # how long a Dask scheduler has to answer before its address is refused
_CLUSTER_SCHEMES = ("tcp", "tls")


def available_cpus() -> int:
    """CPUs this process may run on (affinity mask where the OS has one, else the CPU count)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # pragma: no cover - macOS, Windows
        return max(1, os.cpu_count() or 1)


def default_threads() -> int:
    """The default ``--threads``: available CPUs, at most `MAX_THREADS`."""
    return min(MAX_THREADS, available_cpus())


def check_threads(threads: int | None, *, name: str = "threads") -> int:
    """``threads`` as an int >= 1 (None: `default_threads`).

    Raises:
        ValueError: not an integer >= 1.
    """
    if threads is None:
        return default_threads()
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"{name} = {threads!r}: allowed an integer >= 1")
    return threads


_ALLOWED_CLUSTER = ("allowed: the address of a running Dask scheduler, tcp://HOST:PORT or "
                    "tls://HOST:PORT (e.g. tcp://127.0.0.1:8786 from `dask scheduler`), or none "
                    "to run on this machine")


def _cluster_address(address: object, name: str) -> str:
    """``address`` checked for form only: tcp:// or tls://, a host and a port 1-65535."""
    if not isinstance(address, str) or not address.strip():
        raise ValueError(f"{name} {address!r}: not an address; {_ALLOWED_CLUSTER}")
    try:
        parts = urlsplit(address.strip())
        port = parts.port
    except ValueError:  # an unclosed [IPv6 bracket; a port not a number, or out of range
        parts, port = urlsplit(""), None
    if (parts.scheme not in _CLUSTER_SCHEMES or not parts.hostname or port is None or port < 1
            or parts.path or parts.query or parts.fragment):
        raise ValueError(f"{name} {address!r}: not of the form SCHEME://HOST:PORT with SCHEME tcp "
                         f"or tls and PORT 1-65535; {_ALLOWED_CLUSTER}")
    return address.strip()


def _connect(address: object, name: str):
    """A ``distributed.Client`` of the scheduler at ``address`` (checked first).

    Raises:
        ValueError: a malformed address, distributed not installed, tls:// without TLS
            settings, or no scheduler answering within `CLUSTER_TIMEOUT_S` (plus a second).
    """
    address = _cluster_address(address, name)
    try:
        from distributed import Client
    except ImportError:
        raise ValueError(f"{name} {address!r}: Dask distributed is not installed (pip install "
                         "'softhand[cluster]'); without a cluster, batches run on this machine"
                         ) from None
    if address.startswith("tls://"):
        from distributed.security import Security

        if Security().get_connection_args("client")["ssl_context"] is None:
            raise ValueError(f"{name} {address!r}: tls:// needs the TLS settings of the Dask "
                             "configuration (distributed.comm.tls.ca-file, .client.cert, "
                             f".client.key), and there are none; {_ALLOWED_CLUSTER}")
    box: dict[str, Any] = {}
    lock = threading.Lock()

    def attempt() -> None:
        try:
            client = Client(address, timeout=CLUSTER_TIMEOUT_S, set_as_default=False)
        except Exception as exc:
            _close_half_made(exc, Client)
            box["error"] = exc
            return
        with lock:
            if "late" not in box:
                box["client"] = client
                return
        client.close()  # connected after the wait was over

    # Client's own timeout does not bound a server that accepts and never answers (seen with
    # distributed 2026.8: it waits for ever), so the wait is bounded here; such an attempt is
    # left to its daemon thread
    thread = threading.Thread(target=attempt, name="softhand-cluster-connect", daemon=True)
    thread.start()
    thread.join(CLUSTER_TIMEOUT_S + 1.0)
    with lock:
        box["late"] = True
        if "client" in box:
            return box["client"]
    exc = box.get("error")
    if exc is None or isinstance(exc, (OSError, TimeoutError)):
        raise ValueError(f"{name} {address!r}: no Dask scheduler answered within "
                         f"{CLUSTER_TIMEOUT_S:g} s; {_ALLOWED_CLUSTER}")
    # anything else is a peer that answered but not in Dask's protocol: its bytes read as a
    # frame length gave MemoryError ("Unable to allocate 3.07 EiB"), or a bad frame
    raise ValueError(f"{name} {address!r}: not a Dask scheduler (something answers there, but "
                     f"not in Dask's protocol: {_one_line(exc)[0]}); {_ALLOWED_CLUSTER}")


def _close_half_made(exc: BaseException, client_type: type) -> None:
    """Close the Client that raised ``exc`` in its constructor, here and briefly: left to the
    garbage collector, its ``__del__`` waits 10 s on a peer that is not a scheduler and prints
    a traceback ("Exception ignored in: Client.__del__") when the command has already said
    why it stopped."""
    tb = exc.__traceback__
    while tb is not None:
        me = tb.tb_frame.f_locals.get("self")
        if isinstance(me, client_type):
            with contextlib.suppress(Exception):
                me.close(timeout=1)
            me._Client__loop = None  # its __del__ has nothing left to close
        tb = tb.tb_next
    exc.__traceback__ = None


def check_cluster(address: str, *, name: str = "cluster") -> str:
    """``address`` if a Dask scheduler answers there (the check `run_tasks` makes before
    any work, for callers that check their inputs before theirs).

    Raises:
        ValueError: naming ``name`` and the value: a malformed address, Dask distributed not
            installed, or no scheduler answering within `CLUSTER_TIMEOUT_S`.
    """
    client = _connect(address, name)
    client.close()
    return address.strip()


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
        errors: failed tasks and why (`TaskError` from workers, the exception in-process).
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


#: What a worker sends back for one task: key, succeeded, result or (class name, message),
#: the warnings it raised (`_portable`)
_Done = tuple[Hashable, bool, Any, list[tuple]]


def _init_worker() -> None:
    """Local worker start-up: Ctrl-C is the main process's to handle."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@dataclass(frozen=True)
class _Job:
    """One task as sent to a worker: an object, not a tuple, because older Dask (2024.1) reads
    a tuple that starts with a function, nested in a task's arguments, as a task of its own."""

    fn: Callable
    key: Hashable
    args: tuple


def _call(job: _Job) -> _Done:
    """Run one task in a worker, BLAS single-threaded; its warnings (under the worker's
    filters) go back with it."""
    fn, key, args = job.fn, job.key, job.args
    with warnings.catch_warnings(record=True) as caught, single_threaded_blas():
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


def _one_line(exc: BaseException) -> tuple[str, str]:
    return type(exc).__name__, " ".join(str(exc).split())


def _loky_backend():
    """joblib's loky backend: workers that ignore Ctrl-C (`_init_worker`) and are
    stopped when the batch ends."""
    from joblib.parallel import LokyBackend

    class BatchLokyBackend(LokyBackend):
        """joblib keeps loky workers for the next call (idle up to 5 min); these are shut down
        with the batch, as the spawn pool was, so that the next batch starts workers that see
        ``sys.path`` and the modules as they are then, and no idle worker outlives a batch."""

        def configure(self, *args, **kwargs) -> int:
            return super().configure(*args, initializer=_init_worker, **kwargs)

        def terminate(self) -> None:
            workers = self._workers  # None after an abort (killed already)
            super().terminate()
            if workers is not None:
                workers.terminate(kill_workers=False)  # idle: they exit; waits for them

    return BatchLokyBackend(inner_max_num_threads=1)  # OMP/OpenBLAS/MKL at 1 in the workers


def _on_loky(fn: Callable, tasks: Sequence[tuple[Hashable, tuple]],
             jobs: int) -> Iterator[_Done]:
    """The tasks on ``jobs`` local loky worker processes, as each finishes.

    A worker process that dies (killed, out of memory) stops the batch (joblib terminates the
    others): every task not finished by then comes back failed, with why."""
    from joblib import Parallel, delayed

    parallel = Parallel(n_jobs=jobs, backend=_loky_backend(), return_as="generator_unordered",
                        batch_size=1, max_nbytes=None)
    outputs = parallel(delayed(_call)(_Job(fn, key, args)) for key, args in tasks)
    left = dict.fromkeys(key for key, _ in tasks)
    try:
        for out in outputs:
            left.pop(out[0], None)
            yield out
    except Exception as exc:
        kind, text = _one_line(exc)
        for key in list(left):
            yield key, False, (kind, f"{text} (the batch stopped before this task finished)"), []
    finally:
        with warnings.catch_warnings():  # closed early (Ctrl-C): joblib warns that it cancelled
            warnings.simplefilter("ignore")
            outputs.close()


def _on_cluster(fn: Callable, tasks: Sequence[tuple[Hashable, tuple]],
                client) -> Iterator[_Done]:
    """The tasks on the Dask cluster of ``client``, as each finishes; closes the client.

    Each task is one future (``Client.submit``, priorities in input order), so that progress is
    per task and Ctrl-C cancels exactly this batch's tasks."""
    from distributed import as_completed

    batch = f"softhand-{getattr(fn, '__name__', 'task')}-{uuid.uuid4().hex[:8]}"
    pending: dict[str, tuple[Hashable, Any]] = {}  # dask key: (task key, future)
    try:
        for i, (key, args) in enumerate(tasks):
            future = client.submit(_call, _Job(fn, key, args), key=f"{batch}-{i}",
                                   priority=len(tasks) - i, retries=0)
            pending[future.key] = key, future
        for future in as_completed([f for _, f in pending.values()], loop=client.loop):
            key, _ = pending.pop(future.key)
            try:
                out = future.result()
            except Exception as exc:  # the worker died (KilledWorker), the task was cancelled
                out = key, False, _one_line(exc), []
            future.release()
            yield out
    finally:
        if pending:  # Ctrl-C: the tasks not started are dropped, running ones run out
            with contextlib.suppress(Exception):
                client.cancel([f for _, f in pending.values()], force=True)
        client.close()


def run_tasks(fn: Callable[..., Any], tasks: Sequence[tuple[Hashable, tuple]], *,
              threads: int | None = None, cluster: str | None = None,
              on_done: Callable[[Hashable, bool], None] | None = None) -> BatchOutcome:
    """Run ``fn(*args)`` for every ``(key, args)`` of ``tasks``; stop cleanly on Ctrl-C.

    Args:
        fn: a module-level function (it is sent to worker processes by reference: they import
            its module).
        tasks: (key, args) pairs; keys are unique. They start in this order.
        threads: local worker processes (None: `default_threads`), joblib's loky backend;
            1 runs in this process (BLAS single-threaded, Ctrl-C interrupts the running task).
            Not with ``cluster``, whose workers set how many tasks run at once.
        cluster: the address of a Dask distributed scheduler, ``tcp://HOST:PORT`` or
            ``tls://HOST:PORT``: the tasks run on its workers (None: on this machine). It is
            checked before any task starts (`check_cluster`).
        on_done: called in the main process with (key, succeeded) after each task.

    Warnings raised by a task in a worker are sent back with its result and raised again in
    this process (at their own file and line, under this process's filters, each distinct one
    once per batch under the ``default`` action), so that the caller sees and may record them as
    if the task had run here.

    Returns:
        The outcome; a failed task does not stop the others.

    Raises:
        ValueError: ``threads`` not an integer >= 1; ``cluster`` malformed, not reachable within
            `CLUSTER_TIMEOUT_S`, or given with ``threads``.
    """
    client = None
    if cluster is not None:
        if threads is not None:
            raise ValueError(f"threads = {threads!r} with cluster {cluster!r}: the cluster's "
                             "workers set how many tasks run at once; allowed one of the two")
        client = _connect(cluster, "cluster")  # before any work
        jobs = 0
    else:
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
        registry: dict = {}  # the batch's record of warnings shown (_reissue)
        stream = _on_cluster(fn, tasks, client) if client else _on_loky(fn, tasks, jobs)
        try:
            for key, ok, value, caught in stream:
                _reissue(caught, registry)
                if ok:
                    results[key] = value
                else:
                    errors[key] = TaskError(*value)
                if on_done:
                    on_done(key, ok)
        except KeyboardInterrupt:
            interrupted = True
        finally:
            stream.close()  # Ctrl-C between two tasks: the workers stop (local) or are told to
            if client is not None:
                client.close()  # closed already unless Ctrl-C came before the first task
    order = [key for key, _ in tasks]
    return BatchOutcome(results={k: results[k] for k in order if k in results}, errors=errors,
                        missing=[k for k in order if k not in results and k not in errors],
                        interrupted=interrupted)
