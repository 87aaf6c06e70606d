"""The team page of ``selfrepair view`` (issue 29, item 19): a team trace is viewed, not refused.
The payload is checked here against the trace (held cells never overlap: what the reservations
gave the robots; items and poses as the trace says); the page itself in headless Chromium, like
the mission page (tests/test_viewer_browser.py: its browser fixture, its skip policy)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from selfrepair.cli import main
from selfrepair.experiment.teamview import team_payload
from selfrepair.geometry import Heading, Pose
from selfrepair.team.traceformat import TeamTrace
from selfrepair.team.traceread import read_team_trace
from test_viewer_browser import CELL, driver  # noqa: F401  (the module's browser fixture)


@pytest.fixture(scope="module")
def team_page(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, TeamTrace]:
    folder = tmp_path_factory.mktemp("team-view")
    trace = folder / "team.jsonl"
    assert main(["team", "run", "three-robots", "--trace", str(trace)]) == 0
    html = folder / "team.html"
    assert main(["view", str(trace), "-o", str(html)]) == 0
    parsed = read_team_trace(trace)
    assert parsed.other and parsed.acts
    return html, parsed


def _instants(trace: TeamTrace) -> list[int]:
    times = {0} | {t for m in trace.moves for t in (m.start, m.end)}
    times |= {t for a in trace.acts for t in (a.start, a.end)} | {f.at for f in trace.faults}
    times |= {int(o["at"]) for o in trace.other}
    return sorted(times)


def _pose_at(trace: TeamTrace, robot: str, t: int) -> Pose:
    pose = trace.scenario.robot(robot).start
    for m in sorted(trace.moves, key=lambda m: m.start):
        if m.robot == robot and m.end <= t:
            pose = m.after
    return pose


def test_the_payload_follows_the_trace(team_page: tuple[Path, TeamTrace]) -> None:
    _, trace = team_page
    payload = team_payload(trace, max_steps=50_000)
    times = _instants(trace)
    assert [f["at"] for f in payload["frames"]] == times
    for frame in payload["frames"]:
        held = [tuple(c) for r in frame["robots"] for c in r["held"]]
        assert len(held) == len(set(held)), frame["at"]  # no cell held by two robots at once
        for r in frame["robots"]:
            pose = _pose_at(trace, r["name"], frame["at"])
            assert (r["x"], r["y"], r["heading"]) == (pose.x, pose.y, pose.heading.name)
    final = payload["frames"][-1]
    assert final["delivered"] == trace.summary["delivered"] == len(trace.scenario.tasks)
    assert all(i["delivered"] and i["carrier"] is None for i in final["items"])
    assert len(payload["incident"]) + len(payload["repair"]) + len(payload["own-repair"]) == len(
        trace.other
    )


def test_a_team_trace_that_does_not_replay_is_refused(
    team_page: tuple[Path, TeamTrace], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    html, _ = team_page
    trace = html.with_suffix(".jsonl")
    lines = trace.read_text(encoding="utf-8").splitlines()
    bad = tmp_path / "bad.jsonl"
    bad.write_text("\n".join([*lines[:-1], lines[-1].replace('"acts": 13', '"acts": 12')]) + "\n")
    assert '"acts": 13' in lines[-1]
    assert main(["view", str(bad), "-o", str(tmp_path / "bad.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "does not replay: the summary says acts 12" in err


def _drawn(driver: Any, name: str) -> tuple[Pose, int]:  # noqa: F811
    transform, x, y, heading, frame = driver.execute_script(
        "const r = document.getElementById('robot-' + arguments[0]);"
        "return ['transform', 'data-x', 'data-y', 'data-heading', 'data-frame']"
        ".map(n => r.getAttribute(n));",
        name,
    )
    match = re.fullmatch(r"translate\(([-\d.]+) ([-\d.]+)\) rotate\(([-\d.]+)\)", transform)
    assert match is not None, transform
    px, py, angle = (float(v) for v in match.groups())
    drawn = Pose(round(px / CELL - 0.5), round(py / CELL - 0.5), Heading(round(angle / 90) % 4))
    assert drawn == Pose(int(x), int(y), Heading[heading])
    return drawn, int(frame)


def test_the_team_page_shows_every_robot_on_one_timeline(
    driver: Any,  # noqa: F811
    team_page: tuple[Path, TeamTrace],
) -> None:
    html, trace = team_page
    driver.get_log("browser")
    driver.get(html.as_uri())
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == [], errors
    names = [r.name for r in trace.scenario.robots]
    count = driver.execute_script
    assert count("return document.querySelectorAll('[data-robot]').length") == len(names)
    assert count("return document.querySelectorAll('[data-item]').length") == len(
        trace.scenario.tasks
    )
    assert count("return document.querySelectorAll('#timeline [data-act]').length") == len(
        [r for a in trace.acts for r in a.action.robots]
    )
    kinds = [o["type"] for o in trace.other]
    assert count("return document.querySelectorAll('#incidents li').length") == kinds.count(
        "incident"
    )
    assert count("return document.querySelectorAll('#repairs li').length") == kinds.count("repair")
    times = _instants(trace)
    for frame in sorted({0, 1, len(times) // 3, len(times) // 2, len(times) - 1}):
        driver.execute_script(
            "const s = document.getElementById('slider'); s.value = arguments[0];"
            "s.dispatchEvent(new Event('input', {bubbles: true}));",
            frame,
        )
        for name in names:
            assert _drawn(driver, name) == (_pose_at(trace, name, times[frame]), frame)
    delivered = driver.find_element("css selector", "dd[data-fact='delivered']").text
    assert delivered == f"{len(trace.scenario.tasks)} / {len(trace.scenario.tasks)}"
    assert count("return document.querySelectorAll('[data-delivered=\"yes\"]').length") == len(
        trace.scenario.tasks
    )
    repair = next(o for o in trace.other if o["type"] == "repair")
    driver.find_element("css selector", "#repairs li").click()
    frame = times.index(next(t for t in times if t >= repair["at"]))
    assert _drawn(driver, repair["robot"]) == (
        _pose_at(trace, repair["robot"], times[frame]),
        frame,
    )
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == [], errors


def test_the_team_page_has_the_shared_controls(
    driver: Any,  # noqa: F811
    team_page: tuple[Path, TeamTrace],
) -> None:
    """Play, pause and the arrow keys come from the script both pages share (common.js)."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import WebDriverWait

    html, trace = team_page
    driver.get(html.as_uri())
    name = trace.scenario.robots[0].name
    times = _instants(trace)
    body = driver.find_element(By.TAG_NAME, "body")
    for frame in (1, 2):
        body.send_keys(Keys.ARROW_RIGHT)
        assert _drawn(driver, name) == (_pose_at(trace, name, times[frame]), frame)
    body.send_keys(Keys.ARROW_LEFT)
    assert _drawn(driver, name)[1] == 1
    button = driver.find_element(By.ID, "play")
    button.click()
    assert button.text == "Pause"
    WebDriverWait(driver, 20).until(lambda d: _drawn(d, name)[1] >= 4)
    button.click()
    assert button.text == "Play"
    pose, frame = _drawn(driver, name)
    assert pose == _pose_at(trace, name, times[frame])
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == [], errors


def test_a_stored_team_mission_is_viewed_from_its_database(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = tmp_path / "tiny-team.toml"
    config.write_text(
        'kind = "team"\nname = "tiny-team"\n[[mazes]]\nbundled = "wide-short"\n[team]\n'
        'sizes = [2]\n[faults]\ncases = ["immobilised"]\n[[strategies]]\n'
        'name = "team-replacement"\n',
        encoding="utf-8",
    )
    db = tmp_path / "t.sqlite"
    assert main(["experiment", str(config), "--db", str(db), "--jobs", "1"]) == 0
    import sqlite3

    with sqlite3.connect(db) as con:
        (key,) = con.execute("SELECT key FROM missions").fetchone()
    page = tmp_path / "team.html"
    capsys.readouterr()
    assert main(["view", str(db), "--key", key[:8], "-o", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    assert "selfrepair-team-viewer" in text and '"agrees":true' in text and key in text
