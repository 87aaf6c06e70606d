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

Where chunks run is :mod:`selfrepair.experiment.backends`; what a mission measures and how it
is timed (cold, then warm) is :mod:`selfrepair.experiment.timing`. Library code does not print:
progress is reported through the ``on_progress`` callback (the CLI
draws a rich progress bar with it on a terminal).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import suppress
from dataclasses import dataclass

from selfrepair.errors import InputError, ProblemError
from selfrepair.experiment.backends import (
    Chunk,
    ChunkResult,
    MissionFunction,
    Pool,
    check_backend,
    open_pool,
)
from selfrepair.experiment.keys import Mission
from selfrepair.experiment.store import Finished, ResultStore
from selfrepair.experiment.timing import execute_mission

__all__ = ["CHUNK_SECONDS", "RunSummary", "run_missions"]

CHUNK_SECONDS = 0.5
"""Worker time a chunk of missions should take: long enough that sending it and storing its rows
cost little beside it, short enough that a killed run loses little and workers end together."""

MAX_CHUNK = 256
"""At most this many missions per chunk, however fast they are."""

HEARTBEAT_SECONDS = 5.0
"""The driver tells other writers it is alive at least this often while it waits."""

RECHECK_SECONDS = 0.5
"""How often a driver with nothing left to claim looks again at missions other drivers hold."""


@dataclass(frozen=True, slots=True)
class RunSummary:
    """What a run did: missions in the experiment, already stored when it began, run and stored
    by this run, stored meanwhile by other writers sharing the database, and wall time."""

    total: int
    skipped: int
    ran: int
    seconds: float
    elsewhere: int = 0


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
        with open_pool(backend, jobs=jobs, scheduler=scheduler, address=address) as pool:
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
    pool: Pool,
    execute: MissionFunction,
    dispatch: _Dispatch,
    sizes: _ChunkSizes,
    store: ResultStore,
    pending: int,
    on_progress: Callable[[int, int], None] | None,
) -> int:
    """Keep ``pool.depth`` chunks in flight, store each as it returns; the number stored."""
    in_flight: dict[Future[Chunk], Sequence[Mission]] = {}
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

    def observe(self, results: Sequence[ChunkResult]) -> None:
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
