"""Experiment files with a ``[physics]`` section and the bundled ``experiment physics``: each
mission on the lattice simulator and in MuJoCo, paired, with a ``simulator`` column (the
``physics`` extra for the runs; the file checks need no MuJoCo)."""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "osmesa")  # headless rendering, before mujoco is imported

import sqlite3
import textwrap
from pathlib import Path

import pytest

from extras import needs_extra
from selfrepair.cli import main
from selfrepair.cli.experiments import resolve_experiment
from selfrepair.errors import ConfigError
from selfrepair.experiment.config import load_config, parse_config
from selfrepair.experiment.missions import expand

PHYSICS = needs_extra("mujoco", "imageio", extra="physics")

TINY = """\
name = "tiny-physics"
seed = 7

[[mazes]]
bundled = "wide-short"
routes = 1

[faults]
sets = ["FL:F"]

[physics]
{physics}

[[strategies]]
name = "replacement"
tables = ["handwritten"]
recursion = ["guarded"]
"""


def test_the_bundled_physics_experiment_pairs_every_mission_across_the_simulators() -> None:
    cfg = load_config(resolve_experiment("physics"))
    assert cfg.physics is not None and cfg.physics.simulators == ("lattice", "physics")
    missions = expand(cfg)
    # 2 mazes x 4 routes x 12 paper fault sets x 2 strategies x 2 simulators
    assert len(missions) == 2 * 4 * 12 * 2 * 2
    by_simulator: dict[str, list[int]] = {}
    for m in missions:
        by_simulator.setdefault(str(dict(m.labels)["simulator"]), []).append(m.seed)
    assert sorted(by_simulator) == ["lattice", "physics"]
    assert by_simulator["lattice"] == by_simulator["physics"]  # paired: the same seeds in order
    assert len({m.key for m in missions}) == len(missions)


def test_an_experiment_without_a_physics_section_keeps_its_keys() -> None:
    plain = parse_config(TINY.replace("[physics]\n{physics}\n", ""))
    physics = parse_config(TINY.format(physics='simulators = ["lattice"]'))
    (a,) = expand(plain)
    (b,) = expand(physics)
    assert "simulator" not in a.settings and "simulator" not in dict(a.labels)
    assert b.settings["simulator"] == {"name": "lattice"} and a.key != b.key and a.seed == b.seed


@pytest.mark.parametrize(
    ("physics", "line", "expected"),
    [
        ('simulators = ["mujoco"]', 12, "'lattice' or 'physics'"),
        ('simulators = ["physics", "physics"]', 12, "each simulator once"),
        ("simulators = []", 12, ""),
        ("tracked = 3", 12, "boolean"),
        ("speed = 3", 12, "speed"),
    ],
)
def test_a_bad_physics_section_names_file_line_and_expectation(
    physics: str, line: int, expected: str
) -> None:
    with pytest.raises(ConfigError) as err:
        parse_config(TINY.format(physics=physics), source="t.toml")
    text = str(err.value)
    assert text.startswith(f"t.toml:{line}: key 'physics") and expected in text


@PHYSICS
def test_experiment_with_a_physics_section_runs_both_footings(tmp_path: Path, capsys) -> None:
    config = tmp_path / "tiny.toml"
    config.write_text(TINY.format(physics='simulators = ["lattice", "physics"]'))
    db = tmp_path / "r.sqlite"
    assert main(["experiment", str(config), "--db", str(db), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "tiny-physics: per strategy in physics" in out
    assert "the lattice simulator against physics" in out
    (table,) = [line for line in out.splitlines() if line.startswith("| replacement")]
    assert table.split("|")[2:5] == [" 1 ", " 1 ", " 1 (100.0%) "]
    with sqlite3.connect(db) as con:
        rows = con.execute(
            "SELECT simulator, reached, wall_contacts, physics_seconds FROM missions "
            "ORDER BY simulator"
        ).fetchall()
    assert [r[0] for r in rows] == ["lattice", "physics"]
    assert rows[0][2] is None and rows[0][1] == rows[1][1] == 1
    assert rows[1][2] is not None and rows[1][3] > 0


def test_the_physics_experiment_file_documents_its_size() -> None:
    text = textwrap.dedent(Path(resolve_experiment("physics")).read_text())
    assert "192 missions per simulator" in text
