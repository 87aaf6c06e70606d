"""``selfrepair gym-eval``: evaluate a baseline policy on the Gymnasium environment.

Prints the success rate with its Wilson 95% interval and the mean return with a bootstrap 95%
interval (``--json``: the summary and every episode). Gymnasium, SciPy and the environment are
imported inside the command, so ``selfrepair --help`` loads none of them; without the ``gym`` extra
the command says what to install (exit code 2).
"""

import math
from typing import TYPE_CHECKING, Annotated

from selfrepair.cli._app import app, echo, echo_json, limit_option, option
from selfrepair.cli._inputs import Braid, Corridor, DomainOpt, Json
from selfrepair.cli._mission import Recursion
from selfrepair.errors import InputError
from selfrepair.textio import JSONObject

if TYPE_CHECKING:
    from selfrepair.envs.evaluate import Evaluation
    from selfrepair.envs.scenarios import FaultSpec, MazeSpec
    from selfrepair.stats import Interval

__all__ = ["gym_eval"]

PAPER_FAULTS = "paper"
"""The ``--faults`` value that stands for the reference experiment's 12 fault sets."""


@app.command("gym-eval")
def gym_eval(
    policy: Annotated[
        str, option("--policy", "NAME", "replacement, replan or random.")
    ] = "replacement",
    episodes: Annotated[int, option("--episodes", "N", "Episodes to run.", min=1)] = 100,
    seed: Annotated[int, option("--seed", "S", "Seed of the episode seeds.", min=0)] = 0,
    domain: DomainOpt = "four-wheel",
    maze: Annotated[
        list[str] | None,
        option("--maze", "MAZE", "bundled, a bundled name or a maze file (repeatable)."),
    ] = None,
    generate: Annotated[
        list[str] | None,
        option("--generate", "WxH", "A fresh WIDTHxHEIGHT maze per episode (repeatable)."),
    ] = None,
    corridor: Corridor = 1,
    braid: Braid = 0.0,
    routes: Annotated[str, option("--routes", "KIND", "bundled or random.")] = "bundled",
    faults: Annotated[
        list[str] | None,
        option(
            "--faults",
            "FAULTS",
            "A fault set, e.g. FL:F,RL:F (repeatable), or 'paper'; default: every single "
            "and double fault.",
        ),
    ] = None,
    persistence: Annotated[
        list[str] | None,
        option("--persistence", "KIND", "permanent, transient or intermittent (repeatable)."),
    ] = None,
    detection: Annotated[
        list[str] | None, option("--detection", "KIND", "now or on-use (repeatable).")
    ] = None,
    at_max: Annotated[
        int, option("--at-max", "N", "Faults start at a step from 0 to this.", min=0)
    ] = 0,
    table: Annotated[
        str | None, option("--table", "TABLE", "Table file or bundled name (default: per domain).")
    ] = None,
    recursion: Recursion = "flat",
    max_steps: Annotated[
        int | None, option("--max-steps", "N", "Steps per episode (default 4*w*h).", min=1)
    ] = None,
    max_episodes: Annotated[
        int, limit_option("--max-episodes", "Refuse more episodes than this.")
    ] = 10_000,
    as_json: Json = False,
) -> int:
    """Evaluate a baseline policy on the Gymnasium environment.

    Runs selfrepair/FaultyMaze-v0 and reports the success rate and the return.
    """
    try:
        from selfrepair.envs import FaultSpec, FaultyMazeEnv
        from selfrepair.envs.evaluate import evaluate
        from selfrepair.envs.policies import make_policy
    except ImportError as exc:
        raise InputError(
            f"gym-eval needs the gym extra (pip install 'selfrepair[gym]'): {exc}",
            source="gym-eval",
        ) from None
    spec = FaultSpec(
        sets=_fault_sets(faults, domain),
        persistence=tuple(persistence or ("permanent",)),  # type: ignore[arg-type]
        detection=tuple(detection or ("now",)),  # type: ignore[arg-type]
        at=(0, at_max),
    )
    env = FaultyMazeEnv(
        domain=domain,
        mazes=_mazes(maze, generate, corridor, braid),
        routes=routes,
        faults=spec,
        table=table,
        recursion=recursion,
        max_steps=max_steps,
    )
    result = evaluate(env, make_policy(policy), episodes, seed=seed, max_episodes=max_episodes)
    if as_json:
        echo_json(_as_json(result, env.domain.name))
    else:
        _print(result, env.domain.name, spec)
    return 0


def _fault_sets(faults: list[str] | None, domain: str) -> tuple[str, ...] | None:
    if not faults:
        return None
    if faults == [PAPER_FAULTS]:
        from selfrepair.experiment.faultsets import PAPER_FAULT_SETS

        if domain != "four-wheel":
            raise InputError("the paper fault sets are for the four-wheel robot", source="--faults")
        return PAPER_FAULT_SETS
    return tuple(faults)


def _mazes(
    maze: list[str] | None, generate: list[str] | None, corridor: int, braid: float
) -> "list[MazeSpec]":
    from selfrepair.envs.scenarios import MazeGenerator

    specs: list[MazeSpec] = list(maze or [])
    for text in generate or []:
        width, sep, height = text.lower().partition("x")
        if not sep or not width.isdigit() or not height.isdigit():
            raise InputError(f"expected WIDTHxHEIGHT, got {text!r}", source="--generate")
        specs.append(MazeGenerator(int(width), int(height), corridor, braid))
    return specs or ["bundled"]


def _interval(interval: "Interval", digits: int) -> str:
    if math.isnan(interval.low):
        return "n/a"
    return f"[{interval.low:.{digits}f}, {interval.high:.{digits}f}]"


def _print(result: "Evaluation", domain: str, spec: "FaultSpec") -> None:
    n = len(result.episodes)
    level = round(100 * result.success_interval().level)
    mean_steps = sum(e.steps for e in result.episodes) / n
    echo(f"policy {result.policy}, {n} episodes (seed {result.seed}), robot {domain}")
    echo(
        f"success rate {result.success_rate:.3f} ({result.successes}/{n}), "
        f"{level}% Wilson interval {_interval(result.success_interval(), 3)}"
    )
    echo(
        f"mean return {result.mean_return:.2f}, "
        f"{level}% bootstrap interval {_interval(result.return_interval(), 2)}"
    )
    echo(f"mean steps {mean_steps:.1f}")
    gave_up = sum(e.end == "gave_up" for e in result.episodes)
    if gave_up:
        echo(f"gave up (no plan under the known faults) in {gave_up} episodes")


def _as_json(result: "Evaluation", domain: str) -> JSONObject:
    success, ret = result.success_interval(), result.return_interval()
    return {
        "policy": result.policy,
        "domain": domain,
        "seed": result.seed,
        "episodes": len(result.episodes),
        "successes": result.successes,
        "success_rate": result.success_rate,
        "success_interval": [success.low, success.high],
        "mean_return": result.mean_return,
        "return_interval": [ret.low, ret.high],
        "confidence": success.level,
        "runs": [
            {
                "seed": e.seed,
                "maze": e.maze,
                "start": e.start,
                "goal": e.goal,
                "faults": e.faults,
                "end": e.end.value,
                "steps": e.steps,
                "return": e.episode_return,
            }
            for e in result.episodes
        ],
    }
