"""The mission a CLI command would run, captured before it runs.

``selfrepair run`` ends in :func:`selfrepair.execution.executor.run_mission` and ``compare`` in
:func:`selfrepair.experiment.compare.compare_strategies`; both receive the
:class:`~selfrepair.execution.result.MissionSpec` the flags built as their first argument. The
CLI tests that check what a flag does to the mission stop both there, so they test the parsing
and not a whole run.
"""

from __future__ import annotations

from typing import Any

import pytest

from selfrepair.cli import main
from selfrepair.execution import executor
from selfrepair.execution.result import MissionSpec
from selfrepair.experiment import compare as comparing


class _Captured(Exception):
    def __init__(self, spec: MissionSpec) -> None:
        super().__init__()
        self.spec = spec


def _capture(*args: Any, **kwargs: Any) -> None:
    raise _Captured(args[0])


def captured_spec(monkeypatch: pytest.MonkeyPatch, argv: list[str]) -> MissionSpec:
    """The mission ``selfrepair *argv`` (``run`` or ``compare``) builds, without running it."""
    monkeypatch.setattr(executor, "run_mission", _capture)  # what run calls
    monkeypatch.setattr(comparing, "compare_strategies", _capture)  # what compare calls
    with pytest.raises(_Captured) as info:
        main(argv)
    return info.value.spec
