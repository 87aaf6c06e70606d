// selfrepair viewer, the part every page shares (the mission page, viewer.js, and the team page,
// team.js): the payload, the drawing helpers, the maze, the summary table and the controls
// (play, pause, previous, next, slider, speed, keys). A page script runs after this one and
// draws only what is its own.
const viewer = (function () {
  "use strict";

  const NS = "http://www.w3.org/2000/svg";
  const CELL = 10;
  const data = JSON.parse(document.getElementById("mission-data").textContent);

  function svg(tag, attrs, parent) {
    const node = document.createElementNS(NS, tag);
    for (const name in attrs) node.setAttribute(name, String(attrs[name]));
    if (parent) parent.appendChild(node);
    return node;
  }

  function html(tag, text, cls, parent) {
    const node = document.createElement(tag);
    if (text !== undefined && text !== null) node.textContent = text;
    if (cls) node.className = cls;
    if (parent) parent.appendChild(node);
    return node;
  }

  function centre(value) {
    return (value + 0.5) * CELL;
  }

  // Put a robot's drawing `node` at `pose` (cell x, y, the angle of its heading) and record the
  // pose and the frame `k` on it (data-x, data-y, data-heading, data-frame: what tests read).
  function placeRobot(node, pose, k) {
    node.setAttribute("transform", "translate(" + centre(pose.x) + " " + centre(pose.y) +
      ") rotate(" + pose.angle + ")");
    node.setAttribute("data-x", pose.x);
    node.setAttribute("data-y", pose.y);
    node.setAttribute("data-heading", pose.heading);
    node.setAttribute("data-frame", k);
  }

  // The maze in the #map element: a white ground and the walls as one path of horizontal runs,
  // then one group per name of `layers`, in drawing order. Returns the groups by name.
  function drawMaze(maze, layers) {
    const map = document.getElementById("map");
    const width = maze.width * CELL;
    const height = maze.height * CELL;
    map.setAttribute("viewBox", "0 0 " + width + " " + height);
    svg("rect", { x: 0, y: 0, width: width, height: height, fill: "#ffffff" }, map);
    svg("path", {
      d: maze.walls
        .map((r) => "M" + r[0] * CELL + " " + r[1] * CELL + "h" + r[2] * CELL + "v" + CELL +
          "h" + -r[2] * CELL + "z")
        .join(""),
      fill: "#3b3b3b",
    }, map);
    const groups = {};
    for (const name of layers) groups[name] = svg("g", { id: "layer-" + name }, map);
    return groups;
  }

  // The mission summary row in the #summary table, one row per column but the line's type.
  // Cells blocked by world events (and blocked team faults) at a frame's time: grey squares
  // (a changing world); the mission and the team page draw them alike.
  function drawBlocked(layer, cells) {
    while (layer.firstChild) layer.removeChild(layer.firstChild);
    for (const c of cells) {
      svg("rect", {
        x: c[0] * CELL, y: c[1] * CELL, width: CELL, height: CELL, fill: "#9a9a9a",
        class: "blocked-cell", "data-cell": c[0] + "," + c[1],
      }, layer);
    }
  }

  function buildSummary(summary) {
    const table = document.getElementById("summary");
    for (const key of Object.keys(summary)) {
      if (key === "type") continue;
      const row = html("tr", null, null, table);
      html("td", key, null, row);
      const value = summary[key];
      html("td", value === null ? "" : String(value), null, row);
    }
  }

  // The controls over frames 0..last: `show(k)` draws frame k (clamped and rounded here; it
  // also sets the slider) and `current()` says which frame is shown. Returns { stop, play, jump }.
  function controls(last, show, current) {
    const slider = document.getElementById("slider");
    const playButton = document.getElementById("play");
    const speed = document.getElementById("speed");
    let timer = null;
    slider.max = String(last);

    function go(k) {
      show(Math.min(Math.max(Math.round(k), 0), last));
    }

    function stop() {
      if (timer !== null) clearInterval(timer);
      timer = null;
      playButton.textContent = "Play";
    }

    function play() {
      if (current() >= last) go(0);
      timer = setInterval(() => {
        if (current() >= last) {
          stop();
          return;
        }
        go(current() + 1);
      }, 1000 / Number(speed.value));
      playButton.textContent = "Pause";
    }

    function jump(k) {
      stop();
      go(k);
    }

    playButton.addEventListener("click", () => (timer === null ? play() : stop()));
    document.getElementById("prev").addEventListener("click", () => jump(current() - 1));
    document.getElementById("next").addEventListener("click", () => jump(current() + 1));
    slider.addEventListener("input", () => jump(Number(slider.value)));
    speed.addEventListener("change", () => {
      if (timer !== null) {
        stop();
        play();
      }
    });
    document.addEventListener("keydown", (event) => {
      const tag = event.target.tagName;
      if (event.target === slider || tag === "SELECT" || tag === "BUTTON" || tag === "INPUT") return;
      if (event.key === "ArrowRight") jump(current() + 1);
      else if (event.key === "ArrowLeft") jump(current() - 1);
      else if (event.key === " ") {
        event.preventDefault();
        if (timer === null) play();
        else stop();
      }
    });
    return { stop: stop, play: play, jump: jump };
  }

  return {
    NS, CELL, data, svg, html, centre, placeRobot, drawMaze, drawBlocked, buildSummary, controls,
  };
})();
