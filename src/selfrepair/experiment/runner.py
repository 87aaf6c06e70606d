"""Run the missions of an experiment in parallel and store each result as it arrives.

Execution goes through joblib: local worker processes by default (``jobs``), or the ``dask`` or
``ray`` joblib backends on an existing cluster. Whatever the backend, workers only *compute*: each
returns ``(key, metrics, seconds)`` and the driver - this process - writes the row to the
:class:`~selfrepair.experiment.store.ResultStore`, one committed transaction per mission. A run is
resumable: missions whose key is already stored are skipped before any work is sent out.

Library code does not print: progress is reported through the ``on_progress`` callback (the CLI
draws a rich progress bar with it on a terminal).
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, replace

import joblib
from joblib.externals.loky.process_executor import TerminatedWorkerError

from selfrepair.errors import ProblemError, SelfRepairError
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionResult
from selfrepair.experiment.missions import Mission
from selfrepair.experiment.store import ResultStore, Value

__all__ = [
    "BACKENDS",
    "MissionFunction",
    "RunSummary",
    "check_backend",
    "execute_mission",
    "run_missions",
]

MissionFunction = Callable[[Mission], Mapping[str, Value]]
"""Computes one mission's metric row; must be a picklable module-level function."""

BACKENDS = ("local", "dask", "ray")


@dataclass(frozen=True, slots=True)
class RunSummary:
    """What a run did: missions in the experiment, already stored, run now, and wall time."""

    total: int
    skipped: int
    ran: int
    seconds: float


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
    (:func:`~selfrepair.caching.clear_caches`; loaded table files and the compiled planner
    kernels stay), so its first repair pays what a first repair in a fresh process pays:
    ``cold_first_repair_ns``, ``cold_repair_compute_ns``, ``cold_initial_planning_ns``. Then it
    runs ``repeats`` more times **warm** (caches as the runs before left them); every other
    timing column is the median over those warm runs, repair by repair (results are
    deterministic, so the repairs line up). ``timing_repeats`` records ``repeats``.
    """
    from selfrepair.caching import clear_caches
    from selfrepair.execution.executor import run_mission
    from selfrepair.execution.metrics import optimum_ticks
    from selfrepair.experiment.missions import to_spec

    if repeats < 1:
        raise ProblemError(f"repeats must be at least 1, got {repeats}")
    spec = to_spec(mission)
    clear_caches(keep=INPUT_CACHES)
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
        replace(record, latency_ns=_lower_median([r.repairs[i].latency_ns for r in runs]))
        for i, record in enumerate(first.repairs)
    )
    return replace(first, repairs=repairs, initial_planning_ns=planning)


def _lower_median(values: Sequence[int]) -> int:
    ordered = sorted(values)
    return ordered[(len(ordered) - 1) // 2]


def _work(execute: MissionFunction, mission: Mission) -> tuple[str, dict[str, Value], float]:
    """Worker side: run one mission, return its key, metric row and wall time in seconds."""
    t0 = time.perf_counter()
    try:
        row = dict(execute(mission))
    except SelfRepairError as exc:
        # re-raised as a plain-message error: it crosses process boundaries intact
        raise ProblemError(f"mission {mission.key[:12]} ({mission.config}): {exc}") from None
    return mission.key, row, time.perf_counter() - t0


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
) -> RunSummary:
    """Run every mission of ``missions`` not yet in ``store`` and store each result.

    ``on_progress(done, pending)`` is called once before the first result and after each stored
    row. ``backend`` is ``local`` (``jobs`` processes; 1 runs in this process), ``dask``
    (``scheduler`` address of a running cluster) or ``ray`` (``address`` of a running cluster, or
    a local Ray when omitted); on a cluster ``jobs`` is ignored and every worker is used.
    """
    check_backend(backend, jobs=jobs, scheduler=scheduler)
    execute = execute or execute_mission
    t0 = time.perf_counter()
    done_keys = store.keys()
    pending = [m for m in missions if m.key not in done_keys]
    by_key = {m.key: m for m in pending}
    if on_progress is not None:
        on_progress(0, len(pending))
    done = 0
    if pending:
        with _backend(backend, jobs=jobs, scheduler=scheduler, address=address) as (n_jobs, batch):
            try:
                for key, metrics, seconds in _results(n_jobs, batch, execute, pending):
                    store.add(by_key[key], metrics, seconds)
                    done += 1
                    if on_progress is not None:
                        on_progress(done, len(pending))
            except TerminatedWorkerError as exc:
                raise ProblemError(
                    f"a worker process died ({_first_line(exc)}); {done} missions of this run "
                    f"were stored in {store.path}; run the same command again to resume"
                ) from None
    return RunSummary(len(missions), len(missions) - len(pending), done, time.perf_counter() - t0)


def _results(
    n_jobs: int, batch: int | None, execute: MissionFunction, pending: Sequence[Mission]
) -> Iterator[tuple[str, dict[str, Value], float]]:
    """Each mission's result as soon as the driver can store it.

    ``batch`` is ``None`` for backends that stream results in completion order (loky, Dask).
    Ray's joblib backend returns only whole lists, so missions go in batches of ``batch``:
    each batch's rows are stored before the next starts, and a killed run loses at most the
    batch in flight (its rows were never stored, so resuming runs them again).
    """
    if batch is None:
        parallel = joblib.Parallel(n_jobs=n_jobs, return_as="generator_unordered")
        yield from parallel(joblib.delayed(_work)(execute, m) for m in pending)
        return
    with joblib.Parallel(n_jobs=n_jobs, return_as="list") as parallel:
        for i in range(0, len(pending), batch):
            chunk = pending[i : i + batch]
            yield from parallel(joblib.delayed(_work)(execute, m) for m in chunk)


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]


def check_backend(backend: str, *, jobs: int = 1, scheduler: str | None = None) -> None:
    """Raise :class:`ProblemError` for an unknown backend, a bad ``jobs`` or a missing address."""
    if backend not in BACKENDS:
        raise ProblemError(f"unknown backend {backend!r}: expected one of {', '.join(BACKENDS)}")
    if jobs < 1 and jobs != -1:
        raise ProblemError(f"--jobs must be a positive number or -1 (all cores), got {jobs}")
    if backend == "dask" and not scheduler:
        raise ProblemError("--backend dask needs --scheduler ADDRESS (e.g. tcp://host:8786)")


RAY_BATCH_PER_CPU = 4
"""Missions per Ray batch and cluster CPU: enough to keep every CPU busy, few to lose."""


@contextmanager
def _backend(
    backend: str, *, jobs: int, scheduler: str | None, address: str | None
) -> Iterator[tuple[int, int | None]]:
    """Enter the joblib backend; yields the ``n_jobs`` to pass to ``Parallel`` and the batch size
    (``None``: results stream one by one; see :func:`_results`)."""
    with ExitStack() as stack:
        if backend == "local":
            stack.enter_context(joblib.parallel_config(backend="loky"))
            yield jobs, None
        elif backend == "dask":
            client = stack.enter_context(_dask_client(scheduler))
            stack.enter_context(joblib.parallel_config(backend="dask", client=client))
            yield -1, None
        else:
            cpus = _start_ray(address)
            stack.enter_context(joblib.parallel_config(backend="ray"))
            yield -1, RAY_BATCH_PER_CPU * cpus


@contextmanager
def _dask_client(scheduler: str | None) -> Iterator[object]:
    if not scheduler:
        raise ProblemError("--backend dask needs --scheduler ADDRESS (e.g. tcp://host:8786)")
    try:
        from distributed import Client
    except ImportError:
        raise ProblemError(
            "--backend dask needs dask[distributed]: pip install 'selfrepair[dask]'"
        ) from None
    try:
        client = Client(scheduler, set_as_default=False, timeout="20s")  # type: ignore[no-untyped-call]
    except OSError as exc:
        raise ProblemError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
    try:
        yield client
    finally:
        client.close()  # type: ignore[no-untyped-call]


def _start_ray(address: str | None) -> int:
    """Connect to (or start) Ray and register its joblib backend; returns the cluster's CPUs."""
    try:
        import ray
        from ray.util.joblib import register_ray
    except ImportError:
        raise ProblemError("--backend ray needs ray: pip install 'selfrepair[ray]'") from None
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
    register_ray()
    return max(1, int(ray.cluster_resources().get("CPU", 1)))
