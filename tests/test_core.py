"""The replacement core over a toy world with known answers: the three conditions of
:func:`selfrepair.repair.core.walk` and the recursion of :class:`CoreSearch`, independent of any
robot or team (both run on it: tests/test_replacement.py and tests/test_team.py)."""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from dataclasses import dataclass

from selfrepair.repair.core import CoreSearch, Replacement, walk


@dataclass(frozen=True)
class Line:
    """Steps move along a line of cells: ``+1``/``-1``/``+2``; ``walls`` are cells no step may
    end on; ``broken`` are steps that are not healthy. A step binds to itself."""

    walls: frozenset[int] = frozenset()
    broken: frozenset[int] = frozenset()

    def healthy(self, step: int, state: int) -> bool:
        return step not in self.broken

    def advance(self, step: int, state: int) -> tuple[tuple[Hashable, ...], int] | None:
        end = state + step
        return None if end in self.walls else ((step,), end)


TABLE: dict[int, Sequence[Sequence[int]]] = {
    2: ((1, 1), (-1, 1, 1, 1)),
    1: ((2, -1), (-1, 2)),
    -1: ((1, -2),),
}


def test_walk_checks_health_walls_and_guard() -> None:
    assert walk(Line(), (1, 1), 0, frozenset()) == ((1, 1), 2)
    assert walk(Line(broken=frozenset({1})), (1, 1), 0, frozenset()) is None  # condition 1
    assert walk(Line(walls=frozenset({1})), (1, 1), 0, frozenset()) is None  # condition 2
    assert walk(Line(), (1, 1), 0, frozenset({1})) is None  # condition 3
    assert walk(Line(walls=frozenset({3})), (1, 1), 0, frozenset()) == ((1, 1), 2)


def _search(world: Line, recurse: bool) -> CoreSearch[int, int]:
    return CoreSearch(world, lambda a: TABLE.get(a, ()), lambda b, a, d: recurse and d < 2)


def test_first_valid_candidate_in_order() -> None:
    found = _search(Line(), False).replace(2, 0, frozenset({2}), 0)
    assert found == Replacement(2, (1, 1), (1, 1), 0, 0, 1, 2)
    search = _search(Line(walls=frozenset({1})), False)
    assert search.replace(2, 0, frozenset({2}), 0) is None  # both candidates pass cell 1
    assert search.examined == 2
    around = _search(Line(walls=frozenset({-1})), False).replace(1, 0, frozenset({1}), 0)
    assert around is not None and around.candidate == (2, -1) and around.end == 1


def test_a_broken_step_is_replaced_only_when_the_mode_recurses() -> None:
    world = Line(broken=frozenset({1}))
    assert _search(world, False).replace(2, 0, frozenset({2}), 0) is None
    found = _search(world, True).replace(2, 0, frozenset({2}), 0)
    # 1 -> (2, -1) needs 2, which is being replaced (guard); 1 -> (-1, 2) too; so the first
    # candidate fails, and the second (-1, 1, 1, 1) fails on its first 1 for the same reason
    assert found is None
    unguarded = _search(world, True).replace(2, 0, frozenset(), 0)
    assert unguarded is not None and unguarded.actions == (2, -1, 2, -1) and unguarded.depth == 1


def test_deferred_steps_are_followed_unchecked_but_never_first() -> None:
    world = Line(broken=frozenset({1}), walls=frozenset({1}))
    search: CoreSearch[int, int] = CoreSearch(
        world, lambda a: TABLE.get(a, ()), lambda b, a, d: False, frozenset({1}),
        lambda state, b: state + b,
    )  # fmt: skip
    found = search.replace(2, 0, frozenset({2}), 0)
    # (1, 1) would run a deferred step first; (-1, 1, 1, 1) defers its 1s, the second of which
    # ends on the wall at 1 unchecked (it is replaced when it is reached)
    assert found is not None and found.position == 1 and found.deferred == (1, 2, 3)
    assert found.end == 2 and found.examined == 2
