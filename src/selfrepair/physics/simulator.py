"""The physics world playing the :class:`~selfrepair.execution.simulator.Simulator` role, so that
the one mission loop (:func:`selfrepair.execution.executor.run_mission`, with its stepper,
planner and every strategy) drives MuJoCo unchanged.

:class:`PhysicsSimulator` keeps all of the lattice simulator's bookkeeping (the true faults and
their clock, failed attempts, the footprint check that refuses a command sweeping a wall, the
time in ticks) and, for every command that moves, runs the action's wheel commands in a
:class:`~selfrepair.physics.world.PhysicsWorld`, then localises the robot on the lattice: its pose
becomes the physics end pose snapped to the nearest cell and heading
(:func:`~selfrepair.physics.world.snap`). When that differs from where the lattice said the
action ends, :attr:`deviated` is set and the loop replans from the pose the robot is really at.
Each physics step is kept as a :class:`PhysicsStep` (end pose, its error against the lattice,
wall contacts), the data of a physics mission's outcome.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.simulator import Outcome, Simulator
from selfrepair.geometry import Pose
from selfrepair.physics.model import DEFAULT_PARAMS, RobotParams
from selfrepair.physics.tracker import ContinuousPose, LatticeMotion
from selfrepair.physics.world import PhysicsWorld, pose_error, snap
from selfrepair.robots.domain import SomeDomain
from selfrepair.search.problem import make_pose
from selfrepair.world.events import WorldSchedule
from selfrepair.world.maze import Maze

__all__ = ["PhysicsSimulator", "PhysicsStep", "lattice_motion", "wheel_commands"]


@dataclass(frozen=True, slots=True)
class PhysicsStep:
    """One command as physics ran it: the lattice's end pose, the continuous end pose, where
    localisation put the robot, the position error (cells) and heading error (degrees) of the
    continuous end against the lattice's end, and the control updates that touched a wall."""

    step: int
    action: object
    start: Pose
    lattice_end: Pose
    end: ContinuousPose
    snapped: Pose
    position_error: float
    heading_error: float
    wall_contacts: int
    seconds: float


def wheel_commands(domain: SomeDomain, action: object) -> tuple[int, int, int, int]:
    """The four wheel commands (+1, 0, -1; FL, FR, RL, RR) of a four-wheel action."""
    wheels = getattr(action, "wheels", None)
    if wheels is None or len(wheels) != 4:
        from selfrepair.errors import ProblemError

        raise ProblemError(
            f"the physics model drives four wheels; domain {domain.name!r} has action "
            f"{domain.format_action(action)!r} without four wheel commands"
        )
    a, b, c, d = (int(w) for w in wheels)
    return (a, b, c, d)


def lattice_motion(domain: SomeDomain, action: object) -> LatticeMotion:
    """The lattice motion of ``action`` in the robot's frame, read off the domain (from a
    north-facing start: forward is -y, right is +x)."""
    start = Pose(0, 0, domain.canonical.heading)
    end = domain.apply(start, action)
    return LatticeMotion(-end.y, end.x, (end.heading - start.heading + 2) % 4 - 2)


class PhysicsSimulator(Simulator):
    """A :class:`~selfrepair.execution.simulator.Simulator` whose moves run in MuJoCo (see the
    module docstring). ``tracked`` chooses the tracker over open-loop wheel speeds."""

    def __init__(
        self,
        domain: SomeDomain,
        maze: Maze,
        start: Pose,
        schedule: FaultSchedule,
        seed: int = 0,
        *,
        world: WorldSchedule | None = None,
        behaviour: str | None = None,
        params: RobotParams = DEFAULT_PARAMS,
        tracked: bool = True,
        physics: PhysicsWorld | None = None,
    ) -> None:
        super().__init__(domain, maze, start, schedule, seed, world=world, behaviour=behaviour)
        self.params = params
        self.tracked = tracked
        self.physics = physics if physics is not None else PhysicsWorld(maze, start, params)
        """The MuJoCo world (``world`` is the lattice simulator's world events)."""
        self.physics.place(start)
        self.physics_steps: list[PhysicsStep] = []
        self.deviated = False
        self._motions: dict[object, LatticeMotion] = {}

    def advance(self, action: object) -> Outcome:
        """The lattice simulator's step, then, for a move, the physics run and localisation.
        With hidden faults the wheels run the action the fault behaviour says they perform
        (:attr:`last_action`); a failed attempt or a bump leaves the robot where it is while
        its duration passes (the bumper stops the motors at the contact)."""
        start, step = self.pose, self.steps
        status = super().advance(action)
        self.deviated = False
        if status is not Outcome.MOVED:
            if status is not Outcome.COLLISION:  # the robot stays; time passes
                self.physics.settle(self.params.seconds(self.last_duration))
            return status
        performed = self.performed(action)
        lattice_end = self.pose
        motion = self._motions.get(performed)
        if motion is None:
            motion = self._motions[performed] = lattice_motion(self.domain, performed)
        run = self.physics.run(
            wheel_commands(self.domain, performed),
            Fraction(self.last_duration),
            motion=motion if self.tracked else None,
            reference_start=start,
        )
        snapped = snap(run.end)
        position, heading = pose_error(run.end, lattice_end)
        self.physics_steps.append(
            PhysicsStep(
                step,
                action,
                start,
                lattice_end,
                run.end,
                snapped,
                position,
                heading,
                run.wall_contacts,
                run.seconds,
            )
        )
        if snapped != lattice_end:
            self.pose = make_pose(snapped.x, snapped.y, snapped.heading)
            self.deviated = True
        return status
