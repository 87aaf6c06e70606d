"""One vocabulary: each word of the code base defined once (the time unit, the step-source
colours, variant columns, fault-set choice), and every user of it reading that definition."""

from __future__ import annotations

import dataclasses
from fractions import Fraction

from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.three_action import THREE_ACTION


def test_time_unit_is_the_lcm_of_the_duration_denominators() -> None:
    assert FOUR_WHEEL.time_unit == 3  # durations are multiples of 1/3 tick
    assert THREE_ACTION.time_unit == 1
    durations = {"F": Fraction(1, 2), "L": Fraction(2, 3), "R": Fraction(5, 4)}
    odd = dataclasses.replace(THREE_ACTION, name="odd", duration=durations.__getitem__)
    assert odd.time_unit == 12


def test_every_time_scale_is_the_domain_time_unit() -> None:
    from selfrepair.execution.moves import move_table
    from selfrepair.search.lattice import cost_scale
    from selfrepair.tables.enumerate import domain_classes

    for domain in (FOUR_WHEEL, THREE_ACTION):
        assert cost_scale(domain, Fraction(0)) == domain.time_unit
        assert cost_scale(domain, Fraction(1, 2)) == 2 * domain.time_unit
        assert domain_classes(domain).scale == domain.time_unit
        table = move_table(domain, 64)
        moves = [m for ms in table.moves.values() for m in ms]
        assert moves and all(m.units == m.duration * domain.time_unit for m in moves)


def test_every_step_source_has_one_colour_used_by_figures_and_viewer() -> None:
    from selfrepair.execution.result import StepSource
    from selfrepair.experiment import missionplot, plots, viewer
    from selfrepair.experiment.figstyle import SOURCE_COLOURS, colour_of
    from selfrepair.repair.strategies import RepairSource

    assert set(SOURCE_COLOURS) == set(StepSource)
    assert len(set(SOURCE_COLOURS.values())) == len(StepSource)
    assert all(colour_of(s, "?") == SOURCE_COLOURS[StepSource(s)] for s in RepairSource)
    assert colour_of("failed", "#123456") == "#123456"
    for module in (plots, missionplot, viewer):
        assert "SOURCE_COLOURS" not in vars(module) or module.SOURCE_COLOURS is SOURCE_COLOURS


VARIANTS = """\
name = "columns"

[[mazes]]
bundled = "narrow-short"

[faults]
sets = ["FL:F"]

[[strategies]]
name = "replan"

[[strategies]]
name = "replacement"
tables = ["handwritten"]
recursion = ["flat"]
rewrite = [false, true]

[[strategies]]
name = "lookahead"
tables = ["handwritten"]
recursion = ["flat"]
window = [3]
before = [0, 2]
"""


def test_variant_settings_are_columns_of_every_mission() -> None:
    from selfrepair.experiment.config import parse_config
    from selfrepair.experiment.missions import expand

    seen = set()
    for mission in expand(parse_config(VARIANTS)):
        labels = dict(mission.labels)
        options = mission.settings["options"]
        columns = tuple(labels[c] for c in ("strategy", "table", "recursion", "window", "before"))
        seen.add((*columns, labels["rewrite"]))
        rewrite = int(options.get("rewrite", False)) if "table" in options else None
        assert labels["rewrite"] == rewrite
    assert seen == {
        ("replan", None, None, None, None, None),
        ("replacement", "handwritten", "flat", None, None, 0),
        ("replacement", "handwritten", "flat", None, None, 1),
        ("lookahead", "handwritten", "flat", 3, 0, 0),
        ("lookahead", "handwritten", "flat", 3, 2, 0),
    }


def test_fault_sets_are_spread_over_the_parts_the_domain_names() -> None:
    """biting_fault_sets asks the domain (parts_of), never splits fault text; the paper's 12
    sets still follow from the rule (tests/test_measurement.py)."""
    assert FOUR_WHEEL.parts_of(FOUR_WHEEL.faults[0]) == ("FL", "F")
    assert THREE_ACTION.parts_of(THREE_ACTION.faults[0]) == (THREE_ACTION.format_faults(
        (THREE_ACTION.faults[0],)),)  # fmt: skip
