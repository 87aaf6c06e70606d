"""The diagnosis options have one default each, shared by the library, the CLI and experiment
files (issue 24: ``StrategyOptions.confidence`` was 0.05 where the CLI's was 0.01)."""

from __future__ import annotations

import inspect

from selfrepair.cli._mission import MissionOptions
from selfrepair.diagnosis import DEFAULT_CONFIDENCE, DEFAULT_FAULT_PRIOR, DEFAULT_MAX_FAULTS
from selfrepair.experiment.schema import DiagnosisStrategy
from selfrepair.repair.strategies import StrategyOptions


def test_library_cli_and_files_share_the_defaults() -> None:
    library = StrategyOptions()
    assert (library.confidence, library.fault_prior, library.max_faults) == (0.01, 0.05, 2)
    assert library.confidence == DEFAULT_CONFIDENCE
    assert library.fault_prior == DEFAULT_FAULT_PRIOR
    assert library.max_faults == DEFAULT_MAX_FAULTS
    fields = DiagnosisStrategy.model_fields
    assert fields["confidence"].default == DEFAULT_CONFIDENCE
    assert fields["fault_prior"].default == DEFAULT_FAULT_PRIOR
    assert fields["max_faults"].default == DEFAULT_MAX_FAULTS
    cli = inspect.signature(MissionOptions).parameters
    assert cli["confidence"].default == DEFAULT_CONFIDENCE
    assert cli["fault_prior"].default == DEFAULT_FAULT_PRIOR
    assert cli["max_faults"].default == DEFAULT_MAX_FAULTS
