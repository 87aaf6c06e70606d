"""Plan tolerance on every bundled route: the tolerant planner against clearance weights.

For each bundled maze and route and each bundled four-wheel table (flat recursion), this plans
the optimum (w=0), the clearance plans (w=1, w=2) and the hard tolerant plans for single faults
(k=1) and for single and double faults (k=2), and prints, per table, a Markdown table with

* whether the hard k=1 plan exists (``UNSOLVABLE`` from the exact search is the proof that none
  does) and its ticks over the w=0 optimum, next to w=2's;
* the share of (step, fault set) pairs covered for k=1 and k=2 by each plan
  (:func:`selfrepair.repair.tolerance.plan_tolerance`, exact);
* for the soft plans, the gap between the local objective they minimise (pairs whose step itself
  needs a replan) and the uncovered pairs it stands for.

Run: ``python examples/tolerance/routes.py`` (about a minute).
"""

from __future__ import annotations

from fractions import Fraction

from selfrepair.execution.context import mission_context
from selfrepair.execution.result import MissionSpec
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.repair.tolerance import PlanObjective, fault_model, plan_tolerance
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names

TABLES = ("handwritten", "generated-agnostic", "generated-indexed")
PLANS = (
    ("w=0", Fraction(0), None),
    ("w=1", Fraction(1), None),
    ("w=2", Fraction(2), None),
    ("tolerant k=1", Fraction(0), PlanObjective(1)),
    ("tolerant k=2", Fraction(0), PlanObjective(2)),
    ("soft 1 k=2", Fraction(0), PlanObjective(2, Fraction(1))),
)


def main() -> None:
    models = {k: fault_model(FOUR_WHEEL, k) for k in (1, 2)}
    for table in TABLES:
        print(f"\n### {table} (flat)\n")
        print(
            "| route | k=1 plan | ticks over w=0: k=1, w=2 | "
            + " | ".join(f"{name} k=1, k=2" for name, _, _ in PLANS)
            + " |"
        )
        print("|:---|:---|---:|" + "---:|" * len(PLANS))
        totals = {name: [0, 0, 0, 0] for name, _, _ in PLANS}
        local = uncovered = 0  # the soft plans' own objective against the pairs it stands for
        for maze_name in maze_names():
            maze = load_bundled(maze_name)
            for route in bundled_routes(maze_name):
                cells = []
                ticks = {}
                exists = "none (proof)"
                for name, weight, objective in PLANS:
                    spec = MissionSpec(
                        maze,
                        route.start,
                        route.goal,
                        clearance_weight=weight,
                        options=StrategyOptions(table=table, recursion="flat"),
                    )
                    context = mission_context(spec, spec.options.resolved_table())
                    found = context.plan(route.start, route.goal, None, frozenset(), None)
                    if objective is not None:
                        tolerant = mission_context(
                            MissionSpec(
                                maze,
                                route.start,
                                route.goal,
                                objective=objective,
                                options=spec.options,
                            ),
                            context.table,
                        )
                        found = tolerant.plan(route.start, route.goal, None, frozenset(), None)
                    ticks[name] = found.duration
                    shares = []
                    for k, model in models.items():
                        tol = plan_tolerance(context, found.poses, found.actions, model)
                        totals[name][2 * (k - 1)] += tol.covered
                        totals[name][2 * (k - 1) + 1] += tol.pairs
                        shares.append(f"{float(tol.share):.1%}")
                        if name == "tolerant k=1" and k == 1 and tol.tolerant:
                            exists = "exists"
                        if name == "soft 1 k=2" and k == 2:
                            local += tol.replan_steps
                            uncovered += tol.pairs - tol.covered
                    cells.append(", ".join(shares))
                over_k1 = ticks["tolerant k=1"] - ticks["w=0"] if exists == "exists" else "-"
                print(
                    f"| {maze_name} {route.name} | {exists} | {over_k1}, "
                    f"{ticks['w=2'] - ticks['w=0']} | " + " | ".join(cells) + " |"
                )
        print(
            "| all | | | "
            + " | ".join(f"{t[0] / t[1]:.1%}, {t[2] / t[3]:.1%}" for t in totals.values())
            + " |"
        )
        print(
            f"\nSoft plans (1 tick per pair, k=2): {local} (step, fault set) pairs whose step "
            f"needs a replan (the local objective) stand for {uncovered} uncovered pairs."
        )


if __name__ == "__main__":
    main()
