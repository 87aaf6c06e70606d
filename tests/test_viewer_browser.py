"""The viewer page in a real headless Chromium (Debian's ``chromium`` and ``chromium-driver``,
driven by selenium through the system chromedriver; nothing is downloaded).

Without the browser the tests are skipped, with the reason, unless ``SELFREPAIR_REQUIRE_BROWSER=1``
(set by ``.ci/run``), where they fail instead: CI must not pass without running them.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest

from selfrepair.cli import main
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultEvent, FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.trace import Trace, read_trace, spec_from_header, write_trace
from selfrepair.geometry import Pose
from selfrepair.robots import four_wheel
from selfrepair.world.bundled import bundled_routes, load_bundled

CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")
REQUIRED = os.environ.get("SELFREPAIR_REQUIRE_BROWSER") == "1"
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)
CELL = 10  # the page's user units per cell (viewer.js)


def _missing() -> str | None:
    """Why the browser tests cannot run here, or ``None``."""
    for path, package in ((CHROMIUM, "chromium"), (CHROMEDRIVER, "chromium-driver")):
        if not os.access(path, os.X_OK):
            return f"{path} not found (apt-get install -y {package})"
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed (pip install -e '.[dev]')"
    return None


@pytest.fixture(scope="module")
def driver(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    reason = _missing()
    if reason is not None:
        if REQUIRED:
            pytest.fail(f"SELFREPAIR_REQUIRE_BROWSER=1 but {reason}")
        pytest.skip(f"headless browser test: {reason}")
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    options.binary_location = str(CHROMIUM)
    for flag in CHROMIUM_FLAGS:
        options.add_argument(flag)
    options.add_argument(f"--user-data-dir={tmp_path_factory.mktemp('chromium-profile')}")
    options.add_argument("--window-size=1400,1000")
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    # An explicit driver path: selenium uses it and never runs Selenium Manager (no download).
    browser = webdriver.Chrome(service=Service(executable_path=str(CHROMEDRIVER)), options=options)
    try:
        yield browser
    finally:
        browser.quit()


@pytest.fixture(scope="module")
def page(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Trace]:
    """A viewer page (written by the CLI) of a mission with failed attempts and repairs."""
    folder = tmp_path_factory.mktemp("viewer")
    route = bundled_routes("narrow-short")[0]
    events = (
        FaultEvent(four_wheel.parse_fault("FL:F"), at=3),
        FaultEvent(four_wheel.parse_fault("RR:B"), at=2, persistence="transient", duration=6),
    )
    spec = MissionSpec(
        load_bundled("narrow-short"),
        route.start,
        route.goal,
        schedule=FaultSchedule(events, "on-use"),
        seed=3,
    )
    trace_path = folder / "mission.jsonl"
    write_trace(run_mission(spec), trace_path)
    html = folder / "mission.html"
    assert main(["view", str(trace_path), "-o", str(html)]) == 0
    trace = read_trace(trace_path)
    assert trace.repairs and any(s.source == "failed-attempt" for s in trace.steps)
    return html, trace


def _open(driver: Any, html: Path) -> list[dict[str, Any]]:
    """Load the page; returns the browser log entries of the load."""
    driver.get_log("browser")  # drop anything older
    driver.get(html.as_uri())
    return list(driver.get_log("browser"))


def _robot(driver: Any) -> tuple[Pose, int]:
    """The robot's pose as drawn (from its SVG transform) and the frame the page says it shows.

    All attributes are read in one script call: while the page plays, separate reads could see
    two different frames."""
    from selfrepair.geometry import Heading

    transform, data_x, data_y, heading, frame = driver.execute_script(
        "const r = document.getElementById('robot');"
        "return ['transform', 'data-x', 'data-y', 'data-heading', 'data-frame']"
        ".map(name => r.getAttribute(name));"
    )
    match = re.fullmatch(r"translate\(([-\d.]+) ([-\d.]+)\) rotate\(([-\d.]+)\)", transform)
    assert match is not None, transform
    x, y, angle = (float(v) for v in match.groups())
    drawn = Pose(round(x / CELL - 0.5), round(y / CELL - 0.5), Heading(round(angle / 90) % 4))
    said = Pose(int(data_x), int(data_y), Heading[heading])
    assert drawn == said
    return drawn, int(frame)


def _expected(trace: Trace, frame: int) -> Pose:
    return trace.steps[frame - 1].end if frame else spec_from_header(trace.header).start


def _drag_slider_to(driver: Any, frame: int) -> None:
    """What dragging the slider does: set its value and fire its input event."""
    driver.execute_script(
        "const s = document.getElementById('slider'); s.value = arguments[0];"
        "s.dispatchEvent(new Event('input', {bubbles: true}));",
        frame,
    )


def test_the_page_loads_without_console_errors(driver: Any, page: tuple[Path, Trace]) -> None:
    html, trace = page
    log = _open(driver, html)
    errors = [e for e in log if e["level"] == "SEVERE"]
    assert errors == [], errors
    assert _robot(driver) == (spec_from_header(trace.header).start, 0)
    count = driver.execute_script("return document.querySelectorAll('#repairs li').length")
    assert count == len(trace.repairs)
    # the initial plan is drawn above the executed path (never hidden under it)
    order = driver.execute_script(
        "return Array.from(document.getElementById('map').children).map(n => n.id)"
    )
    assert order.index("layer-plan") > order.index("layer-executed")
    plan = driver.execute_script("return document.getElementById('plan-dashes').children.length")
    assert plan == len(trace.header["initial_plan"])


def test_the_heat_strip_shows_the_plans_tolerance_per_step(
    driver: Any, page: tuple[Path, Trace]
) -> None:
    """One strip cell per initial-plan step, with the uncovered fault sets of the payload, and
    the plan's cells tinted on the map."""
    html, trace = page
    log = _open(driver, html)
    assert [e for e in log if e["level"] == "SEVERE"] == []
    data = driver.execute_script(
        "return JSON.parse(document.getElementById('mission-data').textContent).tolerance"
    )
    shown = driver.execute_script(
        "return Array.from(document.querySelectorAll('#tolerance-strip rect[data-uncovered]'))"
        ".map(r => Number(r.getAttribute('data-uncovered')))"
    )
    assert shown == [len(s["uncovered"]) for s in data["steps"]]
    assert len(shown) == len(trace.header["initial_plan"])
    visible, title, cells = driver.execute_script(
        "const box = document.getElementById('tolerance');"
        "return [!box.hidden, document.getElementById('tolerance-title').textContent,"
        "document.getElementById('layer-tolerance').children.length]"
    )
    assert visible and title.startswith("Plan tolerance (k=1, 12 fault sets)")
    assert cells > 0
    marks = driver.execute_script(
        "return document.querySelectorAll('#tolerance-strip rect[data-needs]').length"
    )
    assert marks == sum(bool(s["needs_replan"]) for s in data["steps"])


def test_the_slider_moves_the_robot_to_the_pose_of_the_trace(
    driver: Any, page: tuple[Path, Trace]
) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    html, trace = page
    _open(driver, html)
    last = len(trace.steps)
    frames = sorted({1, 2, last // 2, last - 1, last, *(r.step for r in trace.repairs)})
    for frame in frames:
        _drag_slider_to(driver, frame)
        assert _robot(driver) == (_expected(trace, frame), frame)
        shown = driver.execute_script(
            "return document.querySelectorAll("
            "'#layer-executed > [data-step]:not([display=\"none\"])').length"
        )
        assert shown == frame
    slider = driver.find_element(By.ID, "slider")
    slider.send_keys(Keys.HOME)
    assert _robot(driver) == (_expected(trace, 0), 0)
    for frame in (1, 2, 3):
        slider.send_keys(Keys.ARROW_RIGHT)
        assert _robot(driver) == (_expected(trace, frame), frame)
    slider.send_keys(Keys.END)
    assert _robot(driver) == (_expected(trace, last), last)
    now = driver.find_element(By.CSS_SELECTOR, "dd[data-fact='pose']").text
    assert now == str(_expected(trace, last))
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == [], errors


def test_picking_a_repair_jumps_to_it_and_shows_its_source_and_latency(
    driver: Any, page: tuple[Path, Trace]
) -> None:
    from selenium.webdriver.common.by import By

    html, trace = page
    _open(driver, html)
    index = max(range(len(trace.repairs)), key=lambda i: trace.repairs[i].step)
    repair = trace.repairs[index]
    driver.find_element(By.CSS_SELECTOR, f"#repairs li[data-repair='{index}']").click()
    assert _robot(driver) == (repair.pose, repair.step)
    assert driver.find_element(By.ID, "slider").get_attribute("value") == str(repair.step)
    card = driver.find_element(By.ID, "repairs-now").text
    assert repair.status in card and re.search(r"\d (µs|ms)\b", card), card
    if repair.source == "replacement":
        assert f"table candidate index {repair.candidate_index}" in card
    selected = driver.find_elements(By.CSS_SELECTOR, "#repairs li.selected")
    assert [e.get_attribute("data-repair") for e in selected] == [str(index)]
    highlighted = driver.execute_script(
        "return document.getElementById('layer-highlight').children.length"
    )
    assert highlighted == len(repair.actions) + 1  # its path and a ring at its pose


def test_play_advances_and_pause_stops(driver: Any, page: tuple[Path, Trace]) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    html, trace = page
    _open(driver, html)
    button = driver.find_element(By.ID, "play")
    button.click()
    assert button.text == "Pause"
    WebDriverWait(driver, 20).until(lambda d: _robot(d)[1] >= 3)
    button.click()
    assert button.text == "Play"
    pose, frame = _robot(driver)
    assert 3 <= frame <= len(trace.steps) and pose == _expected(trace, frame)


def test_blocked_cells_grey_out_at_their_time(driver: Any, tmp_path: Path) -> None:
    cli = main
    trace_path, html = tmp_path / "w.jsonl", tmp_path / "w.html"
    args = ["run", "narrow-short", "--start", "7,13,W", "--goal", "1,8", "--strategy", "replan"]
    assert (
        cli(
            [
                *args,
                "--events",
                "5,13@0..10;1,12@4..30",
                "--max-wait",
                "100",
                "--trace",
                str(trace_path),
            ]
        )
        == 0
    )
    assert cli(["view", str(trace_path), "-o", str(html)]) == 0
    _open(driver, html)
    world = spec_from_header(read_trace(trace_path).header).world
    ticks, total = [], Fraction(0)
    for step in read_trace(trace_path).steps:
        ticks.append(total)
        total += step.duration
    for frame in (0, len(ticks) // 2, len(ticks) - 1):
        _drag_slider_to(driver, frame)
        drawn = driver.execute_script(
            "return [...document.querySelectorAll('#layer-blocked .blocked-cell')]"
            ".map(r => r.getAttribute('data-cell')).sort();"
        )
        assert drawn == sorted(f"{x},{y}" for x, y in world.blocked_at(ticks[frame]))


def test_the_diagnosis_panel_shows_the_hypotheses_shrinking_and_the_surprises(
    driver: Any, tmp_path: Path
) -> None:
    """Faults hidden: one bar per step with the hypotheses the trace records as still possible,
    one marker per surprise, and the facts of the frame (issue 24 item 6)."""
    from selenium.webdriver.common.by import By

    from selfrepair.diagnosis import ObservationModel
    from selfrepair.diagnosis.cooperative import Observer

    route = bundled_routes("narrow-long")[0]
    schedule = FaultSchedule.permanent(
        four_wheel.FOUR_WHEEL.parse_faults("FL:F"), detection="hidden"
    )
    spec = MissionSpec(
        load_bundled("narrow-long"), route.start, route.goal, schedule=schedule,
        strategy="active-diagnosis", seed=3, observation=ObservationModel(0.05),
        observers=(Observer("t1", 0.05),),
    )  # fmt: skip
    trace_path, html = tmp_path / "h.jsonl", tmp_path / "h.html"
    write_trace(run_mission(spec), trace_path)
    assert main(["view", str(trace_path), "-o", str(html)]) == 0
    log = _open(driver, html)
    assert [e for e in log if e["level"] == "SEVERE"] == []
    trace = read_trace(trace_path)
    alive = [bin(o.belief or 0).count("1") for o in trace.observations if o is not None]
    surprises = [i for i, o in enumerate(trace.observations) if o is not None and o.surprise]
    assert surprises and alive[-1] < 79
    visible, bars, marks = driver.execute_script(
        "return [!document.getElementById('diagnosis').hidden,"
        "[...document.querySelectorAll('#belief-strip rect[data-alive]')]"
        ".map(r => Number(r.getAttribute('data-alive'))),"
        "[...document.querySelectorAll('#belief-strip [data-surprise]')]"
        ".map(r => Number(r.getAttribute('data-surprise')))]"
    )
    assert visible and bars == alive and marks == surprises
    for frame in (0, surprises[0] + 1, len(trace.steps)):
        _drag_slider_to(driver, frame)
        left = driver.find_element(By.CSS_SELECTOR, "dd[data-fact='hypotheses left']").text
        assert left == f"{79 if frame == 0 else alive[frame - 1]} of 79"
        said = driver.find_element(By.CSS_SELECTOR, "dd[data-fact='surprise']").text
        assert said == ("-" if frame == 0 else "yes" if frame - 1 in surprises else "no")
    best = driver.find_element(By.CSS_SELECTOR, "dd[data-fact='most probable']").text
    assert "FL:F" in best


def test_the_diagnosis_panel_stays_hidden_when_the_robot_is_told(
    driver: Any, page: tuple[Path, Trace]
) -> None:
    html, _ = page
    _open(driver, html)
    assert driver.execute_script("return document.getElementById('diagnosis').hidden") is True
