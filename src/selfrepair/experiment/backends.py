"""Where chunks of missions run: this process, local worker processes, Dask or Ray.

A :class:`Pool` runs chunks (lists of missions) through :func:`work_chunk` and gives each back
as a :class:`~concurrent.futures.Future` of its results; the driver
(:mod:`selfrepair.experiment.runner`) keeps enough of them in flight and stores what returns.
Workers only compute; they never touch the store.
"""

from __future__ import annotations

import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import Executor, Future
from contextlib import ExitStack, contextmanager, suppress
from typing import Any, Protocol

from selfrepair.errors import ProblemError, SelfRepairError
from selfrepair.experiment.keys import Mission
from selfrepair.experiment.store import Value

__all__ = [
    "BACKENDS",
    "Chunk",
    "ChunkResult",
    "MissionFunction",
    "Pool",
    "check_backend",
    "open_pool",
    "work_chunk",
    "worker_setup",
]

MissionFunction = Callable[[Mission], Mapping[str, Value]]
"""Computes one mission's metric row; must be a picklable module-level function."""

BACKENDS = ("local", "dask", "ray")

WORKER_IDLE_SECONDS = 60
"""Local worker processes left idle this long exit (a later run in the same process starts new
ones)."""

ChunkResult = tuple[str, dict[str, Value], float]
"""One mission's key, metric row and wall time in seconds, as a worker sends it back."""

Chunk = list[ChunkResult]
"""The results of one chunk, in the order of its missions."""


def _work(execute: MissionFunction, mission: Mission) -> ChunkResult:
    """Worker side: run one mission, return its key, metric row and wall time in seconds."""
    t0 = time.perf_counter()
    try:
        row = dict(execute(mission))
    except SelfRepairError as exc:
        # re-raised as a plain-message error: it crosses process boundaries intact
        raise ProblemError(f"mission {mission.key[:12]} ({mission.config}): {exc}") from None
    return mission.key, row, time.perf_counter() - t0


def work_chunk(execute: MissionFunction, chunk: Sequence[Mission]) -> list[ChunkResult]:
    """Worker side: run a chunk of missions in order; their results travel back together."""
    return [_work(execute, mission) for mission in chunk]


def check_backend(backend: str, *, jobs: int = 1, scheduler: str | None = None) -> None:
    """Raise :class:`ProblemError` for an unknown backend, a bad ``jobs`` or a missing address."""
    if backend not in BACKENDS:
        raise ProblemError(f"unknown backend {backend!r}: expected one of {', '.join(BACKENDS)}")
    if jobs < 1 and jobs != -1:
        raise ProblemError(f"expected jobs >= 1 or -1 (all cores), got {jobs}")
    if backend == "dask" and not scheduler:
        raise ProblemError("the dask backend needs a scheduler address (e.g. tcp://host:8786)")


class Pool(Protocol):
    """Runs chunks: ``slots`` at once, ``depth`` kept in flight (so no worker waits for the
    driver), each as a :class:`~concurrent.futures.Future` of its results."""

    slots: int
    depth: int

    def submit(self, execute: MissionFunction, chunk: Sequence[Mission]) -> Future[Chunk]:
        """Start ``chunk``."""
        ...

    def abort(self) -> None:
        """Stop every chunk still running (after an error or an interrupt)."""
        ...


class _InlinePool:
    """``jobs=1``: chunks run in this process, one at a time, when submitted."""

    slots = 1
    depth = 1

    def submit(self, execute: MissionFunction, chunk: Sequence[Mission]) -> Future[Chunk]:
        future: Future[Chunk] = Future()
        try:
            future.set_result(work_chunk(execute, chunk))
        except Exception as exc:  # the driver re-raises it from future.result()
            future.set_exception(exc)
        return future

    def abort(self) -> None:
        """Nothing runs in the background."""


class _LocalPool:
    """``jobs`` local processes: this one and ``jobs - 1`` worker processes.

    The driver computes too, and runs a chunk whenever the workers have enough queued. Storing a
    chunk's rows costs the driver little beside computing them. How the workers start:

    * On Linux they are **forked from the warm driver**: the driver runs the first chunk itself
      (two missions: it imports the executor, loads the compiled kernels and the inputs), then
      forks the workers, which start with all of that in memory instead of spending about two
      seconds of CPU each importing numpy, numba and the executor and loading the kernels. They
      are stopped when the run ends.
    * Elsewhere (``fork`` is missing or unsafe, as on macOS and Windows) they are loky's reusable
      workers, started at once and importing once, while the driver already runs missions.
    """

    def __init__(self, jobs: int) -> None:
        self.slots = jobs
        self._queued = 2 * (jobs - 1)  # chunks per worker: one running, one waiting
        self.depth = self._queued + 1  # and one here
        self._inline = _InlinePool()
        self._running: list[Future[Chunk]] = []
        self._workers = jobs - 1
        self._forked = _fork_workers()
        self._executor: Executor | None = None if self._forked else self._start()

    def _start(self) -> Executor:
        """The worker pool: forked from this process, or loky's reusable executor."""
        if self._forked:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            return ProcessPoolExecutor(
                max_workers=self._workers,
                mp_context=multiprocessing.get_context("fork"),
                initializer=worker_setup,
                initargs=(os.getpid(),),
            )
        from joblib.externals.loky import get_reusable_executor

        return get_reusable_executor(  # type: ignore[no-any-return]
            max_workers=self._workers,
            timeout=WORKER_IDLE_SECONDS,
            initializer=worker_setup,
            initargs=(os.getpid(),),
        )

    def submit(self, execute: MissionFunction, chunk: Sequence[Mission]) -> Future[Chunk]:
        if self._executor is None:  # forking: the first chunk warms this process up
            future = self._inline.submit(execute, chunk)
            self._executor = self._start()
            return future
        self._running = [f for f in self._running if not f.done()]
        if len(self._running) >= self._queued:
            return self._inline.submit(execute, chunk)
        future = self._executor.submit(work_chunk, execute, list(chunk))
        self._running.append(future)
        return future

    def close(self) -> None:
        """Stop forked workers once the run is over (loky's idle ones time out by themselves)."""
        if self._forked and self._executor is not None:
            self._executor.shutdown(wait=True)

    def abort(self) -> None:
        # Kill the workers first: the executor then fails every pending future as after a
        # worker crash. (loky's shutdown(kill_workers=True) with chunks still queued trips a
        # KeyError in its manager thread, printed as a traceback.)
        if self._executor is None:
            return
        for process in list(getattr(self._executor, "_processes", {}).values()):
            with suppress(ProcessLookupError):
                os.kill(process.pid, signal.SIGKILL)
        self._executor.shutdown(wait=False)


def _fork_workers() -> bool:
    """Whether local workers are forked from the driver: on Linux, where ``fork`` is safe for
    this process (no native threads it cannot clean up; the kernels are numba's, single-threaded),
    and kept out of macOS, where forking a process that loaded system frameworks is not."""
    import multiprocessing

    return sys.platform.startswith("linux") and "fork" in multiprocessing.get_all_start_methods()


class _DaskPool:
    """The workers of a running Dask cluster, through the client's futures executor."""

    def __init__(self, client: Any) -> None:
        self.slots = max(1, sum(client.nthreads().values()))
        self.depth = 2 * self.slots
        self._executor = client.get_executor(pure=False)

    def submit(self, execute: MissionFunction, chunk: Sequence[Mission]) -> Future[Chunk]:
        future: Future[Chunk] = self._executor.submit(work_chunk, execute, list(chunk))
        return future

    def abort(self) -> None:
        self._executor.shutdown(wait=False)  # cancels what is still queued or running


class _RayPool:
    """The CPUs of a Ray cluster, one remote task per chunk."""

    def __init__(self, cpus: int) -> None:
        import ray

        self.slots = cpus
        self.depth = 2 * cpus
        self._remote = ray.remote(work_chunk)
        self._running: list[tuple[Any, Future[Chunk]]] = []

    def submit(self, execute: MissionFunction, chunk: Sequence[Mission]) -> Future[Chunk]:
        ref = self._remote.remote(execute, list(chunk))
        future: Future[Chunk] = ref.future()
        self._running = [(r, f) for r, f in self._running if not f.done()] + [(ref, future)]
        return future

    def abort(self) -> None:
        import ray

        for ref, future in self._running:
            if not future.done():
                ray.cancel(ref, force=True)


@contextmanager
def open_pool(
    backend: str, *, jobs: int, scheduler: str | None, address: str | None
) -> Iterator[Pool]:
    """The pool of ``backend`` (see :func:`selfrepair.experiment.runner.run_missions`), closed
    when the block ends."""
    with ExitStack() as stack:
        if backend == "local" and jobs == 1:
            yield _InlinePool()
        elif backend == "local":
            local = _LocalPool(_cpu_count() if jobs == -1 else jobs)
            stack.callback(local.close)
            yield local
        elif backend == "dask":
            yield _DaskPool(stack.enter_context(_dask_client(scheduler)))
        else:
            yield _RayPool(_start_ray(address))


def _cpu_count() -> int:
    from joblib import cpu_count

    return max(1, int(cpu_count()))


def worker_setup(parent: int) -> None:
    """Run first in every local worker process: leave Ctrl-C to the driver (which stops the
    workers itself), and exit as soon as the driver ``parent`` is gone, however it died."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_exit_with, args=(parent,), daemon=True, name="exit-with").start()


def _exit_with(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(PARENT_POLL_SECONDS)
    os._exit(1)  # no clean-up: the driver that would take the results is dead


PARENT_POLL_SECONDS = 0.2
"""How often a local worker checks that its driver still lives."""


@contextmanager
def _dask_client(scheduler: str | None) -> Iterator[object]:
    if not scheduler:
        raise ProblemError("the dask backend needs a scheduler address (e.g. tcp://host:8786)")
    try:
        from distributed import Client
    except ImportError:
        raise ProblemError(
            "the dask backend needs dask[distributed]: pip install 'selfrepair[dask]'"
        ) from None
    try:
        client = Client(scheduler, set_as_default=False, timeout="20s")  # type: ignore[no-untyped-call, unused-ignore]
    except OSError as exc:
        raise ProblemError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
    try:
        yield client
    finally:
        client.close()  # type: ignore[no-untyped-call, unused-ignore]


def _start_ray(address: str | None) -> int:
    """Connect to (or start) Ray; returns the cluster's CPUs."""
    try:
        import ray
    except ImportError:
        raise ProblemError("the ray backend needs ray: pip install 'selfrepair[ray]'") from None
    if not ray.is_initialized():
        try:
            ray.init(
                address=address,
                log_to_driver=False,
                include_dashboard=False,
                logging_level=logging.ERROR,  # Ray's start-up notices are not ours to print
            )
        except ConnectionError as exc:
            raise ProblemError(f"cannot reach the Ray cluster at {address}: {exc}") from None
    return max(1, int(ray.cluster_resources().get("CPU", 1)))
