"""One executor interface for all the cores of this machine or a Dask cluster.

:func:`make_executor` is a context manager yielding a
:class:`concurrent.futures.Executor`:

* ``workers=1`` (no scheduler): :class:`SerialExecutor`, every task run in
  this process when it is submitted;
* otherwise a :class:`~concurrent.futures.ProcessPoolExecutor` with ``workers``
  processes (default: every core, :func:`os.cpu_count`);
* ``scheduler="tcp://host:8786"``: the workers of an existing Dask cluster,
  through ``distributed.Client(address).get_executor()``.  dask.distributed is
  the optional extra ``[cluster]`` (``pip install 'djl-fmu[cluster]'``), imported
  only here, when a scheduler is given (:func:`require_distributed`).

The callers (:func:`harness.workspace.run_map`) submit top-level functions and
collect :class:`concurrent.futures.Future` objects, so one code path serves
the three cases.

Examples
--------
>>> from harness.executors import make_executor
>>> with make_executor(workers=2) as ex:            # doctest: +SKIP
...     print(ex.submit(pow, 2, 10).result())
1024
"""

from __future__ import annotations

import asyncio
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import (
    Executor,
    Future,
    InvalidStateError,
    ProcessPoolExecutor,
    ThreadPoolExecutor,
    as_completed,
)
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from typing import Any

from .errors import HarnessError

__all__ = [
    "CLUSTER_INSTALL",
    "CONNECT_TIMEOUT",
    "ExecutorError",
    "SerialExecutor",
    "describe_executor",
    "executor_workers",
    "make_executor",
    "require_distributed",
    "run_batches",
]

CONNECT_TIMEOUT = 10.0
"""Seconds allowed to reach a Dask scheduler and to find a worker on it."""

CLUSTER_INSTALL = "pip install 'djl-fmu[cluster]'"
"""How to install dask.distributed, the optional extra that a Dask cluster needs."""


class ExecutorError(HarnessError, ValueError):
    """The executor cannot be set up: bad worker count, unreachable Dask scheduler."""


class SerialExecutor(Executor):
    """Run every task in this process, when it is submitted (``workers=1``).

    The returned futures are already done; an exception raised by the task is
    stored in its future, as a process pool would.
    """

    def __init__(self) -> None:
        self._shutdown = False

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        """Run ``fn(*args, **kwargs)`` now; return its (done) future."""
        if self._shutdown:
            raise RuntimeError("cannot schedule new futures after shutdown")
        fut: Future = Future()
        fut.set_running_or_notify_cancel()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as e:  # noqa: BLE001 (stored, as a pool would)
            if isinstance(e, (KeyboardInterrupt, SystemExit)):
                raise
            fut.set_exception(e)
        return fut

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Refuse further tasks (nothing runs in the background)."""
        self._shutdown = True

    @property
    def n_workers(self) -> int:
        """Number of workers: 1."""
        return 1


def _quiet_cancelled_pool_errors() -> None:
    """Silence the pool manager's ``InvalidStateError`` after an interrupted shutdown.

    When the workers die with the pool (a SIGTERM sent to the whole process group) after
    ``shutdown(cancel_futures=True)``, Python 3.11's pool manager thread sets
    ``BrokenProcessPool`` on futures already cancelled and dies printing a traceback
    (``InvalidStateError: CANCELLED``; Python 3.12 ignores that case).  Nothing waits on
    those futures any more: the error is dropped, every other thread exception is printed
    as before.  Installed once, on the first interrupted pool.
    """
    previous = threading.excepthook
    if getattr(previous, "_djl_quiet", False):
        return

    def hook(args: threading.ExceptHookArgs) -> None:
        tb, in_manager = args.exc_traceback, False
        while tb is not None:
            code = tb.tb_frame.f_code
            in_manager |= (code.co_name == "terminate_broken"
                           and code.co_filename.endswith(os.path.join("futures", "process.py")))
            tb = tb.tb_next
        if args.exc_type is InvalidStateError and in_manager:
            return
        previous(args)

    hook._djl_quiet = True  # type: ignore[attr-defined]
    threading.excepthook = hook


#: Seconds an interrupted pool's manager thread is given to wind the pool down.
MANAGER_JOIN_TIMEOUT = 30.0


def _join_pool_manager(manager: threading.Thread) -> None:
    """Wait for an interrupted pool's manager thread to end (at most :data:`MANAGER_JOIN_TIMEOUT`).

    ``shutdown(wait=False)`` returns while the manager thread is still closing the pool.
    Python 3.11's exit hook (``concurrent.futures.process._python_exit``) then writes to
    the manager's wake-up pipe while that thread may be closing it, and prints
    ``OSError: [Errno 9] Bad file descriptor`` with a traceback after the command's last
    line (a race: CPython closes the pipe without the lock the hook would need).  Once the
    manager thread has ended the pipe is marked closed and the hook does nothing.  The hook
    joins that thread anyway, so waiting here costs no time at exit; it only puts the wait
    before the command's message rather than after it.
    """
    manager.join(MANAGER_JOIN_TIMEOUT)


class _ProcessPool(ProcessPoolExecutor):
    """A process pool that says how many processes it has."""

    def __init__(self, max_workers: int) -> None:
        super().__init__(max_workers=max_workers)
        self._n = max_workers

    @property
    def n_workers(self) -> int:
        """Number of worker processes."""
        return self._n


def executor_workers(executor: Executor) -> int:
    """Return the number of tasks an executor runs at once.

    Parameters
    ----------
    executor : Executor
        From :func:`make_executor`, a :class:`~concurrent.futures.ProcessPoolExecutor`,
        a :class:`~concurrent.futures.ThreadPoolExecutor` or a Dask ``ClientExecutor``.

    Returns
    -------
    int
        The worker count (the sum of the worker threads on a Dask cluster; 0
        if unknown).
    """
    n = getattr(executor, "n_workers", None)
    if isinstance(n, int):
        return n
    client = getattr(executor, "_client", None)  # distributed.cfexecutor.ClientExecutor
    if client is not None:
        try:
            info = client.scheduler_info()
            return int(sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()))
        except Exception:  # noqa: BLE001 (a count for reports only)
            return 0
    return int(getattr(executor, "_max_workers", 0) or 0)


def describe_executor(executor: Executor, scheduler: str | None = None) -> str:
    """Where the tasks of an executor run, in words (for summaries).

    Parameters
    ----------
    executor : Executor
        From :func:`make_executor` or any :class:`~concurrent.futures.Executor`.
    scheduler : str, optional
        The Dask scheduler's address, when known.
    """
    if isinstance(executor, SerialExecutor):
        return "in this process"
    if isinstance(executor, ProcessPoolExecutor):
        return "local process pool"
    if isinstance(executor, ThreadPoolExecutor):
        return "thread pool"
    client = getattr(executor, "_client", None)  # distributed's ClientExecutor
    if client is not None:
        try:
            return f"Dask cluster {scheduler or client.scheduler.address}"
        except Exception:  # noqa: BLE001 (a label only)
            return "Dask cluster"
    return type(executor).__name__


def check_workers(workers: int | None) -> int:
    """Return the worker count to use (``None``: every core); refuse one below 1.

    Raises
    ------
    ExecutorError
        If ``workers`` is not an integer >= 1.
    """
    if workers is None:
        return os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ExecutorError(f"the number of workers must be an integer >= 1, got {workers!r}")
    return workers


@contextmanager
def make_executor(workers: int | None = None, scheduler: str | None = None, *,
                  timeout: float | None = None) -> Iterator[Executor]:
    """Executor on the local cores or on a Dask cluster, closed at exit.

    Parameters
    ----------
    workers : int, optional
        Local worker processes (default: :func:`os.cpu_count`); 1 runs every
        task in this process (:class:`SerialExecutor`).  Not used with
        ``scheduler`` (the cluster's workers run the tasks).
    scheduler : str, optional
        Address of a running Dask scheduler, e.g. ``tcp://10.0.0.5:8786``
        (``dask scheduler`` prints it; start workers with ``dask worker ADDRESS``).
    timeout : float, optional
        Seconds to reach the scheduler, and then to find at least one worker
        (default :data:`CONNECT_TIMEOUT`).

    Yields
    ------
    Executor
        ``submit`` returns :class:`concurrent.futures.Future` objects;
        :func:`executor_workers` tells how many run at once.

    Raises
    ------
    ExecutorError
        For a bad worker count, both ``workers`` and ``scheduler``, a scheduler
        that cannot be reached within ``timeout`` (the message gives the
        address) or a cluster without workers.
    """
    if scheduler is None:
        n = check_workers(workers)
        ex: Executor = SerialExecutor() if n == 1 else _ProcessPool(n)
        ok = False
        try:
            yield ex
            ok = True
        finally:
            # on an error or an interrupt, drop the queued tasks and do not wait for them
            manager = getattr(ex, "_executor_manager_thread", None)
            if not ok and isinstance(ex, ProcessPoolExecutor):
                _quiet_cancelled_pool_errors()
            ex.shutdown(wait=ok, cancel_futures=not ok)
            if not ok and isinstance(manager, threading.Thread):
                _join_pool_manager(manager)
        return
    if workers is not None:
        raise ExecutorError("give either a number of local workers or a Dask scheduler, not "
                            "both (the cluster's workers run the tasks)")
    client = connect(scheduler, timeout=CONNECT_TIMEOUT if timeout is None else timeout)
    try:
        cex = client.get_executor(pure=False)
        try:
            yield cex
        finally:
            cex.shutdown(wait=False)
    finally:
        client.close()


def require_distributed() -> None:
    """Import dask.distributed, or say how to install it (the extra ``[cluster]``).

    Only a Dask cluster (``scheduler=...``, ``--scheduler``) needs it; the local cores
    do not.

    Raises
    ------
    ExecutorError
        When it cannot be imported: the message names :data:`CLUSTER_INSTALL`.
    """
    try:
        import distributed  # noqa: F401  (deferred: dask.distributed is heavy to import)
    except ImportError as e:
        raise ExecutorError(
            f"running on a Dask cluster (a scheduler address) needs dask.distributed, which "
            f"is not installed ({e}): install it with {CLUSTER_INSTALL} (from a source "
            f"checkout: pip install '.[cluster]'), or run on this machine's cores (no "
            f"scheduler)") from None


def connect(address: str, *, timeout: float | None = None) -> Any:
    """Connect to a Dask scheduler that has at least one worker.

    Parameters
    ----------
    address : str
        Scheduler address, e.g. ``tcp://host:8786`` (``host:8786`` works too).
    timeout : float, optional
        Seconds to reach it, and then to find a worker (default
        :data:`CONNECT_TIMEOUT`).

    Returns
    -------
    distributed.Client

    Raises
    ------
    ExecutorError
        If dask.distributed is not installed (the message says how to install it), or
        the scheduler cannot be reached, or has no worker, within ``timeout``.
    """
    timeout = CONNECT_TIMEOUT if timeout is None else float(timeout)
    if not isinstance(address, str) or not address.strip():
        raise ExecutorError(f"bad Dask scheduler address {address!r} (e.g. tcp://host:8786)")
    require_distributed()
    from distributed import Client  # deferred: dask.distributed is heavy to import
    what = _probe(address, timeout)
    if what != "Scheduler":
        raise ExecutorError(f"{address} is a Dask {what}, not a scheduler: give the address "
                            f"'dask scheduler' prints (e.g. tcp://host:8786)")
    try:
        client = Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as e:
        raise ExecutorError(f"cannot connect to the Dask scheduler at {address}: "
                            f"{_first_line(e)}") from None
    try:
        client.wait_for_workers(1, timeout=timeout)
    except (OSError, TimeoutError) as e:
        client.close()
        raise ExecutorError(f"the Dask scheduler at {address} has no worker after "
                            f"{timeout:g} s ({type(e).__name__}); start some with "
                            f"'dask worker {address}'") from None
    return client


def _first_line(e: BaseException) -> str:
    text = str(e).strip()
    return text.splitlines()[0] if text else type(e).__name__


def _probe(address: str, timeout: float) -> str:
    """Ask the server at ``address`` what it is (``"Scheduler"``, ``"Worker"``...).

    The handshake runs in its own thread and event loop, bounded by ``timeout``:
    ``distributed.Client`` can wait forever on a port that accepts connections
    but never answers.
    """
    async def identity() -> Any:
        from distributed.core import rpc  # deferred: dask.distributed is heavy to import

        async with rpc(address, timeout=timeout) as r:
            return await r.identity()

    def run() -> Any:
        # distributed's own connect timeout says why (refused, unknown host) when it
        # fires; this one is for a server that accepts but does not answer
        return asyncio.run(asyncio.wait_for(identity(), timeout + 2.0))

    pool = ThreadPoolExecutor(1)
    try:
        info = pool.submit(run).result(timeout + 10.0)
    except (OSError, TimeoutError, ValueError, TypeError) as e:
        raise ExecutorError(f"cannot reach the Dask scheduler at {address} within "
                            f"{timeout:g} s ({_first_line(e)}); start one with 'dask "
                            f"scheduler' and give the address it prints") from None
    except Exception as e:  # noqa: BLE001 (a server that is not Dask)
        raise ExecutorError(f"no Dask scheduler answers at {address} "
                            f"({type(e).__name__}: {_first_line(e)})") from None
    finally:
        pool.shutdown(wait=False)
    return str(info.get("type", "server")) if isinstance(info, dict) else "server"


class LineProgress:
    """A tqdm-like progress for a log (not a terminal): a line now and then on stderr.

    ``update(n)`` counts; a line is printed at the first update, then at most every
    ``interval`` seconds, and at ``close()`` (the total and the time taken).

    Parameters
    ----------
    total : int
        What will be counted.
    desc : str
        Start of each line, e.g. ``map X``.
    unit : str
        What is counted, e.g. ``moves``.
    interval : float
        Least time between two lines (s).
    stream : file, optional
        Where to print (default: ``sys.stderr`` at each line).
    """

    def __init__(self, total: int, desc: str, unit: str = "moves", interval: float = 10.0,
                 stream: Any = None) -> None:
        self.total, self.desc, self.unit, self.interval = total, desc, unit, interval
        self.stream = stream
        self.n = 0
        self._t0 = time.perf_counter()
        self._last: float | None = None
        self._printed = -1

    def _line(self, final: bool = False) -> None:
        el = time.perf_counter() - self._t0
        text = f"{self.desc}: {self.n}/{self.total} {self.unit}"
        if final:
            text += f" done in {el:.1f} s"
        else:
            text += f" ({100.0 * self.n / max(self.total, 1):.0f} %), {el:.0f} s"
            if 0 < self.n < self.total:
                text += f", about {el * (self.total - self.n) / self.n:.0f} s left"
        print(text, file=self.stream or sys.stderr, flush=True)
        self._printed = self.n

    def update(self, n: int = 1) -> None:
        """Count ``n`` more; print a line if the last one is ``interval`` old."""
        self.n += n
        now = time.perf_counter()
        if self.n < self.total and (self._last is None or now - self._last >= self.interval):
            self._last = now
            self._line()

    def close(self) -> None:
        """Print the last line (how many, how long) once all are counted; else nothing."""
        if self.n >= self.total:
            self._line(final=True)


def run_batches(ex: Executor, task: Callable[..., Any], args: Sequence[Any],
                items: Sequence[Any], batch: int, *, error: type[Exception],
                passthrough: type[Exception],
                progress: Any = None, on_serial_end: Callable[[], None] | None = None
                ) -> tuple[list[Any], float]:
    """Run ``task(*args, start, items[start:start + batch])`` for every batch on an executor.

    The results come back in the order of the batches, whatever the executor
    and the order of completion.

    Parameters
    ----------
    ex : Executor
        From :func:`make_executor` (a :class:`SerialExecutor` runs each batch as
        it is submitted, so progress shows as it goes).
    task : callable
        A picklable top-level function; its result has a ``rows`` sequence
        (for the progress bar).
    args : sequence
        Leading arguments of every call.
    items : sequence
        What the batches are cut from (e.g. the moves of a map).
    batch : int
        Items per task.
    error : type of Exception
        Raised for any failure, with a message that says what failed.
    passthrough : type of Exception
        A failure the task reports itself (its message is kept as it is).
    progress : tqdm-like, optional
        Updated with the number of rows of each result, closed at the end.
    on_serial_end : callable, optional
        Called at the end when ``ex`` is serial (e.g. to close a session that
        the tasks kept in this process).

    Returns
    -------
    results : list
        One per batch, in batch order.
    wall : float
        Wall-clock time (s).
    """
    starts = list(range(0, len(items), batch))
    results: list[Any] = [None] * len(starts)
    serial = isinstance(ex, SerialExecutor)

    def collect(i: int, fut: Future) -> None:
        try:
            res = fut.result()
        except passthrough as e:
            raise error(str(e)) from None
        except BrokenProcessPool as e:
            raise error(f"a worker process died ({e})") from None
        except Exception as e:  # noqa: BLE001 (remote failures arrive as any type)
            hint = ""
            if isinstance(e, ModuleNotFoundError) or "harness" in str(e):
                hint = " (is this package installed on every Dask worker?)"
            raise error(f"a batch of moves failed: {type(e).__name__}: {e}{hint}") from None
        results[i] = res
        if progress is not None:
            progress.update(len(res.rows))

    t0 = time.perf_counter()
    futures: dict[Future, int] = {}
    try:
        for i, start in enumerate(starts):
            fut = ex.submit(task, *args, start, items[start:start + batch])
            if serial:
                collect(i, fut)  # already done: report progress as it goes
            else:
                futures[fut] = i
        for fut in as_completed(futures):
            collect(futures[fut], fut)
    except BaseException:
        for f in futures:
            f.cancel()
        raise
    finally:
        if progress is not None:
            progress.close()
        if serial and on_serial_end is not None:
            on_serial_end()
    return results, time.perf_counter() - t0
