"""Run the missions of an experiment in parallel and store their results in batches.

Missions go out in *chunks*: each task a worker receives is a list of missions (sized to take
about :data:`CHUNK_SECONDS`), and its results come back together and are stored in one
transaction. Workers are long-lived processes that import the executor once. Local worker
processes (``jobs``; forked from the warm driver on Linux, loky's elsewhere) are the default;
the ``dask`` and ``ray`` backends use an existing cluster. Whatever the backend, workers only
*compute*; the driver - this process - writes the :class:`~selfrepair.experiment.store.ResultStore`.

A run is resumable and shareable: missions whose key is already stored are skipped, and every
chunk is *claimed* in the store before it is sent out, so several drivers started on one
database (on one host or several) split the missions between them instead of running them
twice. A driver that finds the rest claimed by another live driver waits for it to store them,
and takes over the claims of one that died.

Local workers leave with their driver: they ignore Ctrl-C (the driver stops them), and each
watches its parent and exits as soon as the driver is gone, also after a ``SIGKILL``.

Library code does not print: progress is reported through the ``on_progress`` callback (the CLI
draws a rich progress bar with it on a terminal).
"""

from __future__ import annotations

import json
import logging
import math
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Executor, Future, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import ExitStack, contextmanager, suppress
from dataclasses import dataclass, replace
from typing import Any, Protocol

from selfrepair.errors import InputError, ProblemError, SelfRepairError
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionResult
from selfrepair.experiment.keys import Mission
from selfrepair.experiment.store import Finished, ResultStore, Value

__all__ = [
    "BACKENDS",
    "CHUNK_SECONDS",
    "MissionFunction",
    "RunSummary",
    "check_backend",
    "execute_mission",
    "run_missions",
]

MissionFunction = Callable[[Mission], Mapping[str, Value]]
"""Computes one mission's metric row; must be a picklable module-level function."""

BACKENDS = ("local", "dask", "ray")

CHUNK_SECONDS = 0.5
"""Worker time a chunk of missions should take: long enough that sending it and storing its rows
cost little beside it, short enough that a killed run loses little and workers end together."""

MAX_CHUNK = 256
"""At most this many missions per chunk, however fast they are."""

WORKER_IDLE_SECONDS = 60
"""Local worker processes left idle this long exit (a later run in the same process starts new
ones)."""

HEARTBEAT_SECONDS = 5.0
"""The driver tells other writers it is alive at least this often while it waits."""

RECHECK_SECONDS = 0.5
"""How often a driver with nothing left to claim looks again at missions other drivers hold."""

_Result = tuple[str, dict[str, Value], float]


@dataclass(frozen=True, slots=True)
class RunSummary:
    """What a run did: missions in the experiment, already stored when it began, run and stored
    by this run, stored meanwhile by other writers sharing the database, and wall time."""

    total: int
    skipped: int
    ran: int
    seconds: float
    elsewhere: int = 0


DUPLICATE_COLUMNS = frozenset(
    (
        "maze",
        "strategy",
        "table",
        "recursion",
        "window",
        "faults",
        "detection",
        "seed",
        "clearance_weight",
    )
)
"""Executor row columns left out because the mission's own label columns already hold them
(in the experiment's naming; the exact values are in the ``config`` JSON)."""


INPUT_CACHES = ("bundled tables", "table files", "fault-free optimum ticks")
"""Caches of inputs (table files) and of the common reference, kept across the cold run: filling
them happens before any clock starts, so clearing them would only slow the sweep down."""


def execute_mission(mission: Mission, *, repeats: int = 1) -> Mapping[str, Value]:
    """The real mission function: run the executor on ``missions.to_spec(mission)``.

    The row is :meth:`MissionResult.to_row` (columns in docs/replacement.md) without the
    :data:`DUPLICATE_COLUMNS`, plus ``repair_sources`` (JSON list, the source of each repair in
    the order of ``repair_latencies_ns``), ``plan_ticks_before`` (duration of the initial,
    fault-free plan), ``extra_ticks`` (ticks taken minus that, for reached missions),
    ``maze_free_cells``, ``optimum_ticks``/``ticks_over_optimum`` (against the fault-free optimum
    at clearance weight 0 on the same route, the same reference for every variant) and the
    timing columns below.

    Timing, with one cache policy for every strategy (docs/experiments.md): the mission first
    runs **cold**, after every derived-data cache of the process is emptied
    (:func:`~selfrepair.caching.clear_caches`; loaded table files, the compiled planner kernels,
    the simulator's move tables, which no plan or repair reads, and the tables' candidate
    geometry, which every mission computes before its clocks start, stay), so its first repair
    pays what a first repair in a fresh process pays: ``cold_first_repair_ns``,
    ``cold_repair_compute_ns``, ``cold_initial_planning_ns``. Then it runs ``repeats`` more times
    **warm** (caches as the runs before left them); every other
    timing column is the median over those warm runs, repair by repair (results are
    deterministic, so the repairs line up). ``timing_repeats`` records ``repeats``.
    """
    from selfrepair.caching import clear_caches
    from selfrepair.execution.executor import run_mission
    from selfrepair.execution.metrics import optimum_ticks
    from selfrepair.execution.moves import SIMULATION_CACHES
    from selfrepair.experiment.missions import to_spec
    from selfrepair.repair.replacement import PREFILLED_CACHES

    if repeats < 1:
        raise ProblemError(f"repeats must be at least 1, got {repeats}")
    spec = to_spec(mission)
    clear_caches(keep=(*INPUT_CACHES, *SIMULATION_CACHES, *PREFILLED_CACHES))
    cold = run_mission(spec)
    warm = [run_mission(spec) for _ in range(repeats)]
    result = _median_timings(warm)
    row = {
        k: v
        for k, v in mission_row(result, optimum=optimum_ticks(spec)).items()
        if k not in DUPLICATE_COLUMNS
    }
    plan_ticks = result.initial_plan.duration
    row["repair_sources"] = json.dumps(
        [r.repair.source if r.repair.status == "repaired" else "failed" for r in result.repairs]
    )
    row["plan_ticks_before"] = float(plan_ticks)
    row["extra_ticks"] = float(result.ticks - plan_ticks) if result.reached else None
    row["maze_free_cells"] = int((~result.spec.maze.walls).sum())
    cold_latencies = [r.latency_ns for r in cold.repairs]
    row["first_repair_ns"] = result.repairs[0].latency_ns if result.repairs else None
    row["cold_first_repair_ns"] = cold_latencies[0] if cold_latencies else None
    row["cold_repair_compute_ns"] = sum(cold_latencies)
    row["cold_initial_planning_ns"] = cold.initial_planning_ns
    row["timing_repeats"] = repeats
    return row


def _median_timings(runs: Sequence[MissionResult]) -> MissionResult:
    """The first run with each timing replaced by its (lower) median over ``runs``: the initial
    planning time, and each repair's latency position by position."""
    first = runs[0]
    if len(runs) == 1:
        return first
    counts = {len(r.repairs) for r in runs}
    planning = _lower_median([r.initial_planning_ns for r in runs])
    if counts != {len(first.repairs)}:  # never expected: missions are deterministic
        return replace(first, initial_planning_ns=planning)
    repairs = tuple(
        record._replace(latency_ns=_lower_median([r.repairs[i].latency_ns for r in runs]))
        for i, record in enumerate(first.repairs)
    )
    return replace(first, repairs=repairs, initial_planning_ns=planning)


def _lower_median(values: Sequence[int]) -> int:
    ordered = sorted(values)
    return ordered[(len(ordered) - 1) // 2]


def _work(execute: MissionFunction, mission: Mission) -> _Result:
    """Worker side: run one mission, return its key, metric row and wall time in seconds."""
    t0 = time.perf_counter()
    try:
        row = dict(execute(mission))
    except SelfRepairError as exc:
        # re-raised as a plain-message error: it crosses process boundaries intact
        raise ProblemError(f"mission {mission.key[:12]} ({mission.config}): {exc}") from None
    return mission.key, row, time.perf_counter() - t0


def work_chunk(execute: MissionFunction, chunk: Sequence[Mission]) -> list[_Result]:
    """Worker side: run a chunk of missions in order; their results travel back together."""
    return [_work(execute, mission) for mission in chunk]


def run_missions(
    missions: Sequence[Mission],
    store: ResultStore,
    *,
    jobs: int = 1,
    backend: str = "local",
    scheduler: str | None = None,
    address: str | None = None,
    execute: MissionFunction | None = None,
    on_progress: Callable[[int, int], None] | None = None,
    chunk_size: int | None = None,
) -> RunSummary:
    """Run every mission of ``missions`` not yet in ``store`` and store the results.

    ``on_progress(done, pending)`` is called once before the first result and after each stored
    chunk; ``done`` counts the missions stored since the start, by this run or by another writer
    sharing the database. ``backend`` is ``local`` (``jobs`` processes; 1 runs in this process),
    ``dask`` (``scheduler`` address of a running cluster) or ``ray`` (``address`` of a running
    cluster, or a local Ray when omitted); on a cluster ``jobs`` is ignored and every worker is
    used. ``chunk_size`` fixes the missions per chunk (default: sized to :data:`CHUNK_SECONDS`).

    On any exception, including ``KeyboardInterrupt``, the missions in flight are abandoned
    (local workers are stopped), this run's claims are freed and the exception propagates; every
    stored row stays, and running again resumes.
    """
    check_backend(backend, jobs=jobs, scheduler=scheduler)
    if chunk_size is not None and chunk_size < 1:
        raise ProblemError(f"chunk_size must be a positive number, got {chunk_size}")
    execute = execute or execute_mission
    t0 = time.perf_counter()
    stored = store.keys()
    unique = {m.key: m for m in missions}
    pending = [m for m in unique.values() if m.key not in stored]
    skipped = len(unique) - len(pending)
    if on_progress is not None:
        on_progress(0, len(pending))
    if not pending:
        return RunSummary(len(missions), skipped, 0, time.perf_counter() - t0)
    store.start_writing()
    try:
        with _pool(backend, jobs=jobs, scheduler=scheduler, address=address) as pool:
            sizes = _ChunkSizes(pool.slots, chunk_size)
            dispatch = _Dispatch(store, pending)
            ran = _drive(pool, execute, dispatch, sizes, store, len(pending), on_progress)
    finally:
        # A claim that cannot be freed now (the database failed) is freed by the next writer
        # that sees this process gone; it must not hide what ended the run.
        with suppress(InputError):
            store.stop_writing()
    return RunSummary(
        len(missions), skipped, ran, time.perf_counter() - t0, elsewhere=dispatch.elsewhere
    )


def _drive(
    pool: _Pool,
    execute: MissionFunction,
    dispatch: _Dispatch,
    sizes: _ChunkSizes,
    store: ResultStore,
    pending: int,
    on_progress: Callable[[int, int], None] | None,
) -> int:
    """Keep ``pool.depth`` chunks in flight, store each as it returns; the number stored."""
    in_flight: dict[Future[list[_Result]], Sequence[Mission]] = {}
    ran = 0
    try:
        while True:
            while len(in_flight) < pool.depth:
                chunk = dispatch.next_chunk(sizes.size(dispatch.unclaimed))
                if not chunk:
                    break
                in_flight[pool.submit(execute, chunk)] = chunk
            if not in_flight:
                if not dispatch.waiting:
                    return ran
                time.sleep(RECHECK_SECONDS)  # the rest is another writer's: wait for it
                if on_progress is not None:
                    on_progress(ran + dispatch.elsewhere, pending)
                continue
            finished, _ = wait(in_flight, timeout=HEARTBEAT_SECONDS, return_when=FIRST_COMPLETED)
            if not finished:
                store.heartbeat()
            for future in finished:
                sent = in_flight.pop(future)
                results = future.result()
                sizes.observe(results)
                by_key = {m.key: m for m in sent}
                ran += store.add_many([Finished(by_key[k], row, s) for k, row, s in results])
                if on_progress is not None:
                    on_progress(ran + dispatch.elsewhere, pending)
    except BrokenProcessPool as exc:  # from a result, or from submitting to the broken pool
        pool.abort()
        raise ProblemError(
            f"a worker process died ({_first_line(exc)}); {ran} missions of this run were "
            f"stored in {store.path}; run the same command again to resume"
        ) from None
    except BaseException:
        pool.abort()
        raise


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]


class _ChunkSizes:
    """Chunk sizes that take about :data:`CHUNK_SECONDS` each, and split the last missions
    between the workers so they finish together."""

    def __init__(self, slots: int, fixed: int | None) -> None:
        self._slots = slots
        self._fixed = fixed
        self._seconds = 0.0
        self._count = 0

    def observe(self, results: Sequence[_Result]) -> None:
        self._seconds += sum(seconds for _, _, seconds in results)
        self._count += len(results)

    def size(self, remaining: int) -> int:
        if self._fixed is not None:
            return self._fixed
        if self._count == 0:
            return 2  # the first chunks tell how long a mission takes
        per_mission = max(self._seconds / self._count, 1e-6)
        size = min(MAX_CHUNK, round(CHUNK_SECONDS / per_mission))
        share = math.ceil(remaining / (2 * self._slots))
        return max(1, min(size, share))


class _Dispatch:
    """Hands out chunks of pending missions that this writer has claimed in the store.

    Missions another live writer has claimed are set aside and looked at again once this
    writer has nothing else to claim: by then they are stored (counted in :attr:`elsewhere`), or
    their writer died and they can be claimed.
    """

    def __init__(self, store: ResultStore, pending: Sequence[Mission]) -> None:
        self._store = store
        self._by_key = {m.key: m for m in pending}
        self._order = [m.key for m in pending]
        self._cursor = 0
        self._held: dict[str, None] = {}  # keys claimed by other writers, in order
        self._last_recheck = 0.0
        self.elsewhere = 0
        """Missions found stored by other writers after this run began."""

    @property
    def unclaimed(self) -> int:
        """Missions not yet looked at, plus those other writers hold."""
        return len(self._order) - self._cursor + len(self._held)

    @property
    def waiting(self) -> bool:
        """Whether missions held by other writers remain to be seen stored."""
        return bool(self._held)

    def next_chunk(self, size: int) -> list[Mission]:
        """Up to ``size`` missions this writer now owns; empty when none can be had now."""
        while self._cursor < len(self._order):
            window = self._order[self._cursor : self._cursor + max(4 * size, 64)]
            claim = self._store.claim(window, size)
            self._cursor += claim.examined
            self.elsewhere += len(claim.stored)
            self._held.update(dict.fromkeys(claim.busy))
            if claim.claimed:
                return [self._by_key[k] for k in claim.claimed]
        if self._held and time.monotonic() - self._last_recheck >= RECHECK_SECONDS:
            return self._take_held(size)
        return []

    def _take_held(self, size: int) -> list[Mission]:
        self._last_recheck = time.monotonic()
        claim = self._store.claim(list(self._held), size)
        for key in (*claim.stored, *claim.claimed):
            del self._held[key]
        self.elsewhere += len(claim.stored)
        return [self._by_key[k] for k in claim.claimed]


def check_backend(backend: str, *, jobs: int = 1, scheduler: str | None = None) -> None:
    """Raise :class:`ProblemError` for an unknown backend, a bad ``jobs`` or a missing address."""
    if backend not in BACKENDS:
        raise ProblemError(f"unknown backend {backend!r}: expected one of {', '.join(BACKENDS)}")
    if jobs < 1 and jobs != -1:
        raise ProblemError(f"expected jobs >= 1 or -1 (all cores), got {jobs}")
    if backend == "dask" and not scheduler:
        raise ProblemError("the dask backend needs a scheduler address (e.g. tcp://host:8786)")


# --- where chunks run ----------------------------------------------------------------------------


class _Pool(Protocol):
    """Runs chunks: ``slots`` at once, ``depth`` kept in flight (so no worker waits for the
    driver), each as a :class:`~concurrent.futures.Future` of its results."""

    slots: int
    depth: int

    def submit(self, execute: MissionFunction, chunk: Sequence[Mission]) -> Future[list[_Result]]:
        """Start ``chunk``."""
        ...

    def abort(self) -> None:
        """Stop every chunk still running (after an error or an interrupt)."""
        ...


class _InlinePool:
    """``jobs=1``: chunks run in this process, one at a time, when submitted."""

    slots = 1
    depth = 1

    def submit(self, execute: MissionFunction, chunk: Sequence[Mission]) -> Future[list[_Result]]:
        future: Future[list[_Result]] = Future()
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
        self._running: list[Future[list[_Result]]] = []
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

    def submit(self, execute: MissionFunction, chunk: Sequence[Mission]) -> Future[list[_Result]]:
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

    def submit(self, execute: MissionFunction, chunk: Sequence[Mission]) -> Future[list[_Result]]:
        future: Future[list[_Result]] = self._executor.submit(work_chunk, execute, list(chunk))
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
        self._running: list[tuple[Any, Future[list[_Result]]]] = []

    def submit(self, execute: MissionFunction, chunk: Sequence[Mission]) -> Future[list[_Result]]:
        ref = self._remote.remote(execute, list(chunk))
        future: Future[list[_Result]] = ref.future()
        self._running = [(r, f) for r, f in self._running if not f.done()] + [(ref, future)]
        return future

    def abort(self) -> None:
        import ray

        for ref, future in self._running:
            if not future.done():
                ray.cancel(ref, force=True)


@contextmanager
def _pool(
    backend: str, *, jobs: int, scheduler: str | None, address: str | None
) -> Iterator[_Pool]:
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
