"""Byte limits of the text inputs that have no count of their own to check: MovingAI scenarios,
route files, experiment files, team scenarios (``max_file_bytes``) and traces
(``max_trace_bytes``).

Each reader refuses a file one byte over its limit before reading it (a file whose content is
also bad gets the limit error, not a parse error) and reads the same file at exactly its size.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from selfrepair import limits
from selfrepair.errors import LimitError, SelfRepairError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultEvent, FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.trace import read_trace, write_trace
from selfrepair.experiment.config import load_config
from selfrepair.experiment.teams import load_experiment
from selfrepair.robots import four_wheel
from selfrepair.team.scenario import Limits
from selfrepair.team.scenario import load_scenario as load_team_scenario
from selfrepair.team.trace import read_team_trace
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.movingai import load_scenario
from selfrepair.world.routes import load_routes, save_routes

DATA = Path(__file__).parent / "data"
PACKAGE_DATA = Path(__file__).parents[1] / "src" / "selfrepair" / "data"


def _scenario(tmp_path: Path) -> Path:
    target = tmp_path / "maze512-1-0.map.scen"
    shutil.copy(DATA / "movingai" / "maze512-1-0.map.scen", target)
    return target


def _routes(tmp_path: Path) -> Path:
    target = tmp_path / "narrow-short.routes"
    save_routes(bundled_routes("narrow-short"), target)
    return target


def _experiment(tmp_path: Path) -> Path:
    target = tmp_path / "paper.toml"
    shutil.copy(PACKAGE_DATA / "experiments" / "paper.toml", target)
    return target


def _team(tmp_path: Path) -> Path:
    target = tmp_path / "three-robots.toml"
    shutil.copy(PACKAGE_DATA / "team" / "three-robots.toml", target)
    return target


def _trace(tmp_path: Path) -> Path:
    route = bundled_routes("narrow-short")[0]
    schedule = FaultSchedule((FaultEvent(four_wheel.parse_fault("FL:F"), at=1),), "now")
    result = run_mission(MissionSpec(load_bundled("narrow-short"), route.start, route.goal,
                                     schedule=schedule, strategy="replan", seed=1))
    target = tmp_path / "mission.jsonl"
    write_trace(result, target)
    return target


Reader = Callable[[Path, int], Any]

# (limit name, how to make a valid file, how to read it with a limit)
CASES: list[tuple[str, Callable[[Path], Path], Reader]] = [
    ("max_file_bytes", _scenario, lambda p, n: load_scenario(p, max_file_bytes=n)),
    ("max_file_bytes", _routes, lambda p, n: load_routes(p, max_file_bytes=n)),
    ("max_file_bytes", _experiment, lambda p, n: load_config(p, max_file_bytes=n)),
    ("max_file_bytes", _experiment, lambda p, n: load_experiment(p, max_file_bytes=n)),
    ("max_file_bytes", _team,
     lambda p, n: load_team_scenario(p, limits=Limits(max_file_bytes=n))),
    ("max_trace_bytes", _trace, lambda p, n: read_trace(p, max_trace_bytes=n)),
]


@pytest.mark.parametrize(("limit", "make", "read"), CASES)
def test_a_file_over_its_byte_limit_is_refused_unread(
    tmp_path: Path, limit: str, make: Callable[[Path], Path], read: Reader
) -> None:
    path = make(tmp_path)
    size = path.stat().st_size
    read(path, size)  # exactly at the limit: read as usual
    path.write_bytes(path.read_bytes() + b"\xff not even UTF-8\n")
    with pytest.raises(LimitError) as caught:
        read(path, size)
    assert caught.value.limit == limit
    message = str(caught.value)
    assert str(path) in message and f"at most {size:,} bytes" in message
    assert f"--{limit.replace('_', '-')}" in message


def test_a_team_trace_over_the_trace_limit_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / "team.jsonl"
    path.write_bytes(b"\xff" * 100)
    with pytest.raises(LimitError) as caught:
        read_team_trace(path, max_trace_bytes=99)
    assert caught.value.limit == "max_trace_bytes"
    with pytest.raises(SelfRepairError) as at_limit:
        read_team_trace(path, max_trace_bytes=100)
    assert not isinstance(at_limit.value, LimitError)  # read, then refused as not UTF-8


def test_the_defaults_are_the_documented_constants() -> None:
    assert limits.MAX_FILE_BYTES == 64 * 1024 * 1024
    assert limits.MAX_TRACE_BYTES == 256 * 1024 * 1024
    docs = (Path(__file__).parents[1] / "docs" / "reliability.md").read_text()
    assert "`max_file_bytes` | `--max-file-bytes` | 67,108,864" in docs
    assert "`max_trace_bytes` | `--max-trace-bytes` | 268,435,456" in docs
