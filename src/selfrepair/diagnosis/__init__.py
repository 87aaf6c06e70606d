"""Diagnosis from observed motion: what the robot observes, and what it believes of its faults.

A robot whose faults are hidden (detection ``hidden``, see :mod:`selfrepair.execution.faults`)
learns of them only by what it observes after each command. This package is generic over domains
and knows no maze, no simulator and no strategy:

- :mod:`~.observation`: an :class:`Observation` (the pose reading after one command, with the
  bump switch and the "command failed" signal where there are such, its source and the noise
  rate of the sensor that made it) and the :class:`ObservationModel` that makes one, seeded;
- :mod:`~.hypotheses`: the :class:`FaultModel`, the domain's fault sets up to ``k`` faults plus
  "none" as hypotheses, what each makes of each command (``Domain.effective``), the prior, and the
  classes of hypotheses that behave identically on every action;
- :mod:`~.belief`: the :class:`FaultBelief` of one robot: the hypotheses still possible (a bit
  set, exact elimination) and the posterior (Bayes with the observation's noise model), updated
  by one observation at a time, from the robot itself or from a teammate that watched it;
- :mod:`~.probes`: the commands that best split the hypotheses still possible (active diagnosis).

See docs/diagnosis.md.
"""

from __future__ import annotations

from selfrepair.diagnosis.belief import DEFAULT_CONFIDENCE, FaultBelief
from selfrepair.diagnosis.hypotheses import (
    DEFAULT_FAULT_PRIOR,
    DEFAULT_MAX_FAULTS,
    FaultModel,
    fault_model,
)
from selfrepair.diagnosis.observation import (
    PERTURBATIONS,
    Observation,
    ObservationModel,
    perturbed,
)
from selfrepair.diagnosis.probeplan import ProbePlanner, isolating_probe
from selfrepair.diagnosis.probes import Probe, best_probe

__all__ = [
    "DEFAULT_CONFIDENCE",
    "DEFAULT_FAULT_PRIOR",
    "DEFAULT_MAX_FAULTS",
    "PERTURBATIONS",
    "FaultBelief",
    "FaultModel",
    "Observation",
    "ObservationModel",
    "Probe",
    "ProbePlanner",
    "best_probe",
    "fault_model",
    "isolating_probe",
    "perturbed",
]
