"""The one splice of the code base: a repair's actions replace the queued actions it consumes.

Every queue of planned actions holds ``(action, tag)`` pairs (the mission stepper tags each
action with its step source; the tolerance check, which needs no tag, uses ``None``), so the
stepper, the team's drives and :mod:`selfrepair.repair.tolerance` splice by this one function.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from itertools import islice, repeat
from typing import TypeVar

__all__ = ["splice"]

A = TypeVar("A")
S = TypeVar("S")


def splice(queue: deque[tuple[A, S]], consumed: int, actions: Sequence[A], tag: S) -> None:
    """Replace the first ``consumed`` queued actions by ``actions`` tagged ``tag``, in place.
    A short repair pops and pushes at the front; one that covers much of the queue (a whole-plan
    rewrite) rebuilds it in C, which is cheaper than popping item by item."""
    if 3 * consumed > len(queue):
        rest = list(islice(queue, consumed, None))
        queue.clear()
        queue.extend(zip(actions, repeat(tag)))
        queue.extend(rest)
        return
    for _ in range(consumed):
        queue.popleft()
    queue.extendleft(zip(reversed(actions), repeat(tag)))
