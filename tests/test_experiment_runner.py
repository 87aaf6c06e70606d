"""Runner: resume skips stored keys, backends agree (local processes, Dask LocalCluster, Ray)."""

from __future__ import annotations

import logging
import sys
from pathlib import Path

import pytest

from extras import need
from selfrepair.errors import ProblemError
from selfrepair.experiment.config import parse_config
from selfrepair.experiment.keys import Mission
from selfrepair.experiment.missions import expand
from selfrepair.experiment.runner import run_missions
from selfrepair.experiment.store import ResultStore, without_timings

CONFIG = """\
name = "runner"
seed = 11
[[mazes]]
bundled = "narrow-short"
[faults]
sets = ["FL:F", "FR:B,RR:B"]
[planner]
clearance_weights = [0, 1]
[[strategies]]
name = "replan"
[[strategies]]
name = "replacement"
tables = ["handwritten"]
recursion = ["flat"]
"""


def fake_mission(mission: Mission) -> dict[str, int | float | str | None]:
    """A stand-in for the executor: a pure function of the mission's configuration and seed."""
    settings = mission.settings
    return {
        "ticks": mission.seed % 97 + len(settings["faults"]),
        "reached": 1,
        "strategy_seen": settings["strategy"],
        "latency_ns": 12345,
    }


def _missions() -> tuple[Mission, ...]:
    return expand(parse_config(CONFIG))


def _rows(path: Path) -> list[dict[str, object]]:
    with ResultStore(path) as store:
        return [without_timings(r) for r in store.rows()]


def test_resume_skips_stored_missions(tmp_path: Path) -> None:
    missions = _missions()
    calls: list[tuple[int, int]] = []
    with ResultStore(tmp_path / "r.sqlite") as store:
        first = run_missions(
            missions[:5], store, execute=fake_mission, on_progress=lambda d, t: calls.append((d, t))
        )
        assert (first.total, first.skipped, first.ran) == (5, 0, 5)
        # once before the first result, then after each stored chunk, ending at all done
        assert calls[0] == (0, 5) and calls[-1] == (5, 5)
        assert [d for d, _ in calls] == sorted({d for d, _ in calls}) and len(calls) >= 3
        second = run_missions(missions, store, execute=fake_mission)
        assert (second.skipped, second.ran) == (5, len(missions) - 5)
        third = run_missions(missions, store, execute=fake_mission)
        assert third.ran == 0
        assert store.count() == len(missions)


def test_local_processes_match_in_process(tmp_path: Path) -> None:
    missions = _missions()
    with ResultStore(tmp_path / "one.sqlite") as store:
        run_missions(missions, store, jobs=1, execute=fake_mission)
    with ResultStore(tmp_path / "two.sqlite") as store:
        run_missions(missions, store, jobs=2, execute=fake_mission)
    assert _rows(tmp_path / "one.sqlite") == _rows(tmp_path / "two.sqlite")
    assert len(_rows(tmp_path / "one.sqlite")) == len(missions)


def pid_mission(mission: Mission) -> dict[str, int | float | str | None]:
    """Records which process ran the mission, and whether that process is a fork of the driver
    made after this module was imported there (a marker module-level value set below)."""
    import os

    return {"pid": os.getpid(), "parent": os.getppid(), "warm": WARM_MARKER}


WARM_MARKER = 0


@pytest.mark.skipif(sys.platform != "linux", reason="local workers are forked on Linux only")
def test_local_workers_are_forked_from_the_warm_driver(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import os

    # a value set in the driver only: a forked worker inherits it, a fresh interpreter would not
    monkeypatch.setattr(sys.modules[__name__], "WARM_MARKER", 7)
    missions = _missions()
    with ResultStore(tmp_path / "r.sqlite") as store:
        run_missions(missions, store, jobs=2, execute=pid_mission, chunk_size=1)
        rows = store.rows()
    by_worker = [r for r in rows if r["pid"] != os.getpid()]
    assert by_worker, "no mission ran in a worker"
    assert all(r["parent"] == os.getpid() and r["warm"] == 7 for r in by_worker)
    assert any(r["pid"] == os.getpid() for r in rows)  # the driver computes too


def test_dask_local_cluster_matches_local(tmp_path: Path) -> None:
    distributed = need("distributed", "dask")
    logging.getLogger("distributed").setLevel(logging.ERROR)
    missions = _missions()
    with ResultStore(tmp_path / "local.sqlite") as store:
        run_missions(missions, store, jobs=1)  # the real executor
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        ResultStore(tmp_path / "dask.sqlite") as store,
    ):
        summary = run_missions(missions, store, backend="dask", scheduler=cluster.scheduler_address)
        assert summary.ran == len(missions)
    local, dask = _rows(tmp_path / "local.sqlite"), _rows(tmp_path / "dask.sqlite")
    assert len(local) == len(missions) and local == dask


def test_backend_misuse_is_a_problem_error(tmp_path: Path) -> None:
    missions = _missions()[:2]
    with ResultStore(tmp_path / "r.sqlite") as store:
        with pytest.raises(ProblemError, match="scheduler address") as dask:
            run_missions(missions, store, backend="dask", execute=fake_mission)
        with pytest.raises(ProblemError, match="unknown backend"):
            run_missions(missions, store, backend="slurm", execute=fake_mission)
        with pytest.raises(ProblemError, match="jobs >= 1") as jobs:
            run_missions(missions, store, jobs=0, execute=fake_mission)
    for caught in (dask, jobs):  # the library names no command-line flag
        assert "--" not in str(caught.value)


@pytest.mark.ray
def test_ray_backend_matches_local(tmp_path: Path) -> None:
    ray = pytest.importorskip("ray")  # opt-in (-m ray), outside CI and its extras policy
    missions = _missions()
    with ResultStore(tmp_path / "local.sqlite") as store:
        run_missions(missions, store, jobs=1)  # the real executor, as Ray workers run it
    try:
        with ResultStore(tmp_path / "ray.sqlite") as store:
            summary = run_missions(missions, store, backend="ray")
            assert summary.ran == len(missions)
    finally:
        ray.shutdown()
    local, remote = _rows(tmp_path / "local.sqlite"), _rows(tmp_path / "ray.sqlite")
    assert len(local) == len(missions) and local == remote


@pytest.mark.parametrize(("jobs", "chunk"), [(1, 1), (1, 3), (2, 1), (2, 5), (2, 1000)])
def test_any_chunking_stores_every_mission_once(tmp_path: Path, jobs: int, chunk: int) -> None:
    """However missions are cut into chunks, each is stored once, with the same row."""
    missions = _missions()
    with ResultStore(tmp_path / "one.sqlite") as store:
        run_missions(missions, store, execute=fake_mission, chunk_size=1)
    with ResultStore(tmp_path / "r.sqlite") as store:
        summary = run_missions(missions, store, jobs=jobs, execute=fake_mission, chunk_size=chunk)
        assert (summary.ran, summary.elsewhere) == (len(missions), 0)
    assert _rows(tmp_path / "r.sqlite") == _rows(tmp_path / "one.sqlite")


def failing_mission(mission: Mission) -> dict[str, int | float | str | None]:
    """A mission function that meets bad input (as the executor would with a broken table)."""
    from selfrepair.errors import TableError

    raise TableError("cannot read table file", source="broken.json")


@pytest.mark.parametrize("jobs", [1, 2])
def test_mission_errors_cross_processes_intact(tmp_path: Path, jobs: int) -> None:
    with ResultStore(tmp_path / "r.sqlite") as store:
        with pytest.raises(ProblemError, match=r"broken\.json: cannot read table file") as info:
            run_missions(_missions()[:3], store, jobs=jobs, execute=failing_mission)
        assert "<input>" not in str(info.value)
        assert store.count() == 0
