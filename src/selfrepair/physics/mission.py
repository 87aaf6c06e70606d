"""Missions in physics: the one mission loop driving a :class:`PhysicsSimulator`.

:func:`run_physics_mission` runs a :class:`~selfrepair.execution.result.MissionSpec` with
:func:`~selfrepair.execution.executor.run_mission` (same planner, same strategies, same stepper)
on a physics simulator and returns the lattice result (its steps are the localised poses, so
traces, metrics and the HTML viewer read it as any other) with a :class:`PhysicsOutcome`: goal
reached, wall contacts, the final pose error against the goal cell, seconds simulated, repairs,
and how often localisation put the robot off its plan.

With ``video`` it also renders the mission headless (MuJoCo's offscreen renderer; set
``MUJOCO_GL=osmesa`` on a machine without a display) from a camera above the maze, one frame
every ``frame_every`` control updates, and writes a GIF or MP4 with imageio.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from selfrepair.execution.executor import run_mission
from selfrepair.execution.result import MissionResult, MissionSpec
from selfrepair.optional import import_extra
from selfrepair.physics.model import DEFAULT_PARAMS, RobotParams
from selfrepair.physics.simulator import PhysicsSimulator, PhysicsStep
from selfrepair.physics.world import PhysicsWorld

__all__ = ["PhysicsMission", "PhysicsOutcome", "VideoSpec", "run_physics_mission"]


@dataclass(frozen=True, slots=True)
class PhysicsOutcome:
    """What a mission did in physics (see the module docstring). ``final_error`` is the distance
    in cells from the robot's continuous end position to the centre of its final (localised)
    cell; ``wall_contacts`` counts control updates (10 ms each by default) with a contact between
    robot and wall; ``deviations`` the moves that localisation put elsewhere than the lattice."""

    reached: bool
    wall_contacts: int
    final_error: float
    seconds: float
    physics_steps: int
    repairs: int
    deviations: int
    max_position_error: float
    max_heading_error: float
    tracked: bool


@dataclass(frozen=True, slots=True)
class PhysicsMission:
    """A mission's lattice result, its physics outcome and every physics step."""

    result: MissionResult
    outcome: PhysicsOutcome
    steps: tuple[PhysicsStep, ...]


@dataclass(frozen=True, slots=True)
class VideoSpec:
    """A video to render: the file (``.gif`` or ``.mp4``), its frame size and rate."""

    path: Path
    width: int = 480
    height: int = 360
    fps: int = 20


class _Recorder:
    """Renders a frame of the world every ``every`` control updates (mutable: the frames)."""

    def __init__(self, world: PhysicsWorld, video: VideoSpec, every: int) -> None:
        mj = world.mj
        self.renderer = mj.Renderer(world.model, video.height, video.width)
        self.every = every
        self.count = 0
        self.frames: list[object] = []

    def __call__(self, world: PhysicsWorld) -> None:
        if self.count % self.every == 0:
            self.renderer.update_scene(world.data, camera="top")
            self.frames.append(self.renderer.render().copy())
        self.count += 1

    def close(self) -> None:
        self.renderer.close()


def run_physics_mission(
    spec: MissionSpec,
    *,
    params: RobotParams = DEFAULT_PARAMS,
    tracked: bool = True,
    video: VideoSpec | None = None,
    xml: str | None = None,
) -> PhysicsMission:
    """Run ``spec`` in physics (see the module docstring); ``xml`` is a robot's own MJCF model
    in place of the generated one (see :class:`~selfrepair.physics.world.PhysicsWorld`)."""
    world = PhysicsWorld(spec.maze, spec.start, params, xml=xml)
    recorder = None
    if video is not None:
        updates_per_second = 1.0 / (params.timestep * params.control_every)
        every = max(1, round(updates_per_second / video.fps))
        recorder = _Recorder(world, video, every)
        world.observer = recorder
    sims: list[PhysicsSimulator] = []

    def make(s: MissionSpec) -> PhysicsSimulator:
        sim = PhysicsSimulator(
            s.domain, s.maze, s.start, s.schedule, s.seed, world=s.world,
            behaviour=s.behaviour, params=params, tracked=tracked, physics=world,
        )  # fmt: skip
        sims.append(sim)
        return sim

    try:
        result = run_mission(spec, simulator=make)
        if recorder is not None and video is not None:
            _write(recorder.frames, video)
    finally:
        if recorder is not None:
            recorder.close()
    sim = sims[0]
    steps = tuple(sim.physics_steps)
    end = world.pose()
    final_error = math.hypot(end.x - result.final_pose.x, end.y + result.final_pose.y)
    outcome = PhysicsOutcome(
        reached=result.reached,
        wall_contacts=sum(s.wall_contacts for s in steps),
        final_error=final_error,
        seconds=world.time,
        physics_steps=world.total_steps,
        repairs=len(result.repairs),
        deviations=sum(1 for s in steps if s.snapped != s.lattice_end),
        max_position_error=max((s.position_error for s in steps), default=0.0),
        max_heading_error=max((s.heading_error for s in steps), default=0.0),
        tracked=tracked,
    )
    return PhysicsMission(result, outcome, steps)


def _write(frames: list[object], video: VideoSpec) -> None:
    """Write the frames with imageio (the ``physics`` extra)."""
    iio = import_extra("imageio.v2", "physics", need="physics videos")
    if video.path.suffix.lower() == ".gif":
        iio.mimsave(video.path, frames, duration=1000 / video.fps, loop=0)
    else:
        iio.mimsave(video.path, frames, fps=video.fps)
