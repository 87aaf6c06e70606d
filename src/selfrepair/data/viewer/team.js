// selfrepair team viewer. Draws the payload that selfrepair.experiment.teamview built: every
// pose, held cell and item place comes from the data; this script only draws and navigates.
(function () {
  "use strict";

  const { CELL, data, svg, html, centre } = viewer;
  const frames = data.frames;
  const last = frames.length - 1;
  const colourOf = {};
  for (const r of data.robots) colourOf[r.name] = r.colour;
  const state = { frame: -1 };

  // --- the map ----------------------------------------------------------------------------------

  const layers = viewer.drawMaze(data.maze, ["blocked", "held", "tasks", "items", "robots"]);

  // Drop-off cells: an outlined square per task, labelled with its item.
  for (const t of data.tasks) {
    svg("rect", {
      x: t.dropoff[0] * CELL + 1, y: t.dropoff[1] * CELL + 1, width: CELL - 2, height: CELL - 2,
      fill: "none", stroke: "#111111", "stroke-width": 0.6, "stroke-dasharray": "1.5 1",
      "data-dropoff": t.item,
    }, layers.tasks);
    svg("text", {
      x: centre(t.dropoff[0]), y: centre(t.dropoff[1]) + 1.6, "font-size": 4.2,
      "text-anchor": "middle", fill: "#6b6b70",
    }, layers.tasks).textContent = t.item;
  }

  const items = {};
  for (const t of data.tasks) {
    const g = svg("g", { id: "item-" + t.item, "data-item": t.item }, layers.items);
    svg("rect", { x: -2.6, y: -2.6, width: 5.2, height: 5.2, fill: "#F0E442",
      stroke: "#111111", "stroke-width": 0.5 }, g);
    svg("title", {}, g).textContent = "item " + t.item;
    items[t.item] = g;
  }

  const robots = {};
  for (const r of data.robots) {
    const g = svg("g", { id: "robot-" + r.name, "data-robot": r.name }, layers.robots);
    svg("polygon", {
      points: [0, -0.45 * CELL, 0.34 * CELL, 0.32 * CELL, -0.34 * CELL, 0.32 * CELL].join(" "),
      fill: r.colour, stroke: "#111111", "stroke-width": 0.07 * CELL,
    }, g);
    if (!r.gripper) {
      svg("circle", { cx: 0, cy: 0.05 * CELL, r: 0.1 * CELL, fill: "#ffffff" }, g);
    }
    svg("title", {}, g).textContent = r.name + (r.gripper ? "" : " (no gripper)");
    robots[r.name] = g;
  }

  // --- the timeline -----------------------------------------------------------------------------

  const timeline = document.getElementById("timeline");
  const TL = { left: 90, right: 990, row: 22, top: 6 };
  const rowCount = data.lanes.length + data.fault_lanes.length;
  const tlHeight = TL.top + Math.max(rowCount, 1) * TL.row + 24;
  timeline.setAttribute("viewBox", "0 0 1000 " + tlHeight);
  const end = Math.max(data.end, 1);

  function tlX(unit) {
    return TL.left + (unit / end) * (TL.right - TL.left);
  }

  function bar(x0, x1, y, h, fill, attrs) {
    return svg("rect", Object.assign({
      x: tlX(x0), y: y, width: Math.max(tlX(x1) - tlX(x0), 1), height: h, fill: fill,
    }, attrs || {}), timeline);
  }

  function jumpTo(frame) {
    nav.jump(frame);
  }

  data.lanes.forEach((lane, i) => {
    const y = TL.top + i * TL.row;
    const label = svg("text", { x: 4, y: y + 13, "font-size": 12, fill: colourOf[lane.robot] },
      timeline);
    label.textContent = lane.robot;
    svg("g", { "data-lane": lane.robot }, timeline);
    for (const m of lane.moves) {
      bar(m[0], m[1], y + 3, 7, data.move_colours[m[2]] || "#555555", { "data-move": lane.robot });
    }
    for (const a of lane.acts) {
      const node = bar(a[0], a[1], y + 11, 6, "#111111", { "data-act": a[2] });
      svg("title", {}, node).textContent = a[2];
    }
  });
  const rowOf = {};
  data.lanes.forEach((lane, i) => { rowOf[lane.robot] = i; });
  function mark(list, shape, fill) {
    for (const e of list) {
      const row = rowOf[e.robot] === undefined ? 0 : rowOf[e.robot];
      const x = tlX(e.at);
      const y = TL.top + row * TL.row + 2;
      const points = shape === "triangle"
        ? [x, y, x + 4, y + 8, x - 4, y + 8]
        : [x, y, x + 4, y + 5, x, y + 10, x - 4, y + 5];
      const node = svg("polygon", { points: points.join(" "), fill: fill, stroke: "#111111",
        "stroke-width": 0.6, class: "repair-marker", "data-frame": e.frame }, timeline);
      svg("title", {}, node).textContent = e.robot + " " + (e.kind || "") + " at tick " + e.tick;
      node.addEventListener("click", () => jumpTo(e.frame));
    }
  }
  mark(data.incident, "triangle", "#D55E00");
  mark(data.repair, "diamond", "#009E73");
  data.fault_lanes.forEach((lane, i) => {
    const y = TL.top + (data.lanes.length + i) * TL.row;
    svg("text", { x: 4, y: y + 13, "font-size": 11, fill: "#D55E00" }, timeline)
      .textContent = "fault " + lane.index;
    for (const s of lane.spans) {
      const node = bar(s[0], s[1] === null ? end : s[1], y + 4, 10, "#D55E00",
        { "data-fault": lane.index, opacity: 0.8 });
      svg("title", {}, node).textContent = lane.text;
    }
  });
  const axisY = TL.top + Math.max(rowCount, 1) * TL.row + 2;
  svg("line", { x1: TL.left, y1: axisY, x2: TL.right, y2: axisY, stroke: "#999999" }, timeline);
  svg("text", { x: TL.right, y: axisY + 14, "font-size": 10, "text-anchor": "end",
    fill: "#6b6b70" }, timeline).textContent = "tick " + frames[last].tick;
  const cursor = svg("line", { x1: TL.left, y1: 0, x2: TL.left, y2: axisY, stroke: "#111111",
    "stroke-width": 1.5, id: "cursor" }, timeline);
  timeline.addEventListener("click", (event) => {
    if (event.target.getAttribute("data-frame") !== null) return;
    const box = timeline.getBoundingClientRect();
    const unit = (((event.clientX - box.left) / box.width) * 1000 - TL.left) /
      (TL.right - TL.left) * end;
    let frame = 0;
    while (frame < last && frames[frame + 1].at <= unit) frame += 1;
    jumpTo(frame);
  });

  // --- the side panel ---------------------------------------------------------------------------

  const origin = data.origin;
  document.getElementById("origin").textContent = (origin.kind === "results"
    ? "Mission " + origin.key.slice(0, 12) + " of experiment " + origin.experiment + " in " +
      origin.source + ", run again from its stored configuration" +
      (origin.agrees ? "." : " (it differs from the stored row: another version made it).")
    : "Team trace " + origin.source + ".") + " Re-simulation: " + data.replay;

  const legend = document.getElementById("legend");
  for (const r of data.robots) {
    const item = html("span", null, null, legend);
    html("span", null, "swatch", item).style.background = r.colour;
    html("span", " " + r.name + (r.gripper ? "" : " (no gripper)"), null, item);
  }
  const sources = new Set(data.lanes.flatMap((lane) => lane.moves.map((m) => m[2])));
  for (const source of Object.keys(data.move_colours).filter((s) => sources.has(s))) {
    const item = html("span", null, null, legend);
    html("span", null, "swatch", item).style.background = data.move_colours[source];
    html("span", " move: " + source, null, item);
  }
  html("span", "\u25B2 incident  \u25C6 repair  black: pick, drop, handover  shaded cells: " +
    "what each robot holds", null, legend);

  function eventList(id, list, text) {
    const node = document.getElementById(id);
    const entries = [];
    for (const e of list) {
      const item = html("li", "tick " + e.tick + ": " + text(e), null, node);
      item.setAttribute("data-frame", e.frame);
      item.addEventListener("click", () => jumpTo(e.frame));
      entries.push([e.frame, item]);
    }
    if (!list.length) html("li", "none", "none", node);
    return entries;
  }
  document.getElementById("incident-count").textContent = "(" + data.incident.length + ")";
  document.getElementById("repair-count").textContent = "(" + data.repair.length + ")";
  const incidentItems = eventList("incidents", data.incident, (e) =>
    e.robot + " " + e.kind + " at " + e.action + " (" + e.load + ")");
  const repairItems = eventList("repairs", data.repair, (e) =>
    e.robot + ": " + e.outcome + " by " + e.source +
    (e.candidate ? " " + e.candidate + " with " + e.helper : "") +
    "; disturbed " + (e.disturbed.join(", ") || "none") + "; " + e.latency +
    (e.lost.length ? "; lost " + e.lost.join(", ") : ""));

  viewer.buildSummary(data.summary);

  // --- one frame --------------------------------------------------------------------------------

  function fill(tbody, rows) {
    tbody.textContent = "";
    for (const cells of rows) {
      const tr = html("tr", null, null, tbody);
      for (const c of cells) html("td", c, null, tr);
    }
  }

  function setFrame(index) {
    const frame = frames[Math.min(Math.max(index, 0), last)];
    const k = frames.indexOf(frame);
    if (k === state.frame) return;
    state.frame = k;
    document.getElementById("slider").value = k;
    document.getElementById("step-label").textContent =
      "instant " + k + " / " + last + ", tick " + frame.tick;
    viewer.drawBlocked(layers.blocked, frame.blocked);
    layers.held.textContent = "";
    for (const r of frame.robots) {
      for (const c of r.held) {
        svg("rect", { x: c[0] * CELL, y: c[1] * CELL, width: CELL, height: CELL,
          fill: colourOf[r.name], opacity: r.moving ? 0.35 : 0.2, "data-held": r.name },
        layers.held);
      }
      viewer.placeRobot(robots[r.name], r, k);
    }
    for (const it of frame.items) {
      const node = items[it.item];
      const dx = it.carrier ? 0.28 * CELL : 0;
      node.setAttribute("transform", "translate(" + (centre(it.x) + dx) + " " +
        (centre(it.y) - dx) + ")");
      node.setAttribute("data-x", it.x);
      node.setAttribute("data-y", it.y);
      node.setAttribute("data-carrier", it.carrier || "");
      node.setAttribute("data-delivered", it.delivered ? "yes" : "no");
      node.setAttribute("opacity", it.delivered ? 0.45 : 1);
    }
    const x = tlX(frame.at);
    cursor.setAttribute("x1", x);
    cursor.setAttribute("x2", x);
    const now = document.getElementById("now");
    now.textContent = "";
    const facts = [
      ["tick", frame.tick],
      ["delivered", frame.delivered + " / " + data.tasks.length],
      ["team faults", frame.faults.length
        ? frame.faults.map((i) => data.fault_lanes[i].text).join("; ") : "none"],
      ["blocked cells", frame.blocked.length
        ? frame.blocked.map((c) => c[0] + "," + c[1]).join(" ") : "none"],
    ];
    for (const [name, value] of facts) {
      html("dt", name, null, now);
      html("dd", value, null, now).setAttribute("data-fact", name);
    }
    document.getElementById("delivered").textContent =
      "(" + frame.delivered + " / " + data.tasks.length + " delivered)";
    fill(document.querySelector("#robots tbody"), frame.robots.map((r) => [
      r.name, r.x + "," + r.y + "," + r.heading, r.carrying || "", r.doing || "",
    ]));
    fill(document.querySelector("#items tbody"), frame.items.map((it, i) => [
      it.item, it.carrier ? "carried by " + it.carrier : it.x + "," + it.y +
        (it.delivered ? " (delivered)" : ""), data.tasks[i].dropoff.join(","),
    ]));
    for (const [f, item] of incidentItems.concat(repairItems)) {
      item.className = f === k ? "selected" : (f > k ? "future" : "");
    }
  }

  // --- controls ---------------------------------------------------------------------------------

  const nav = viewer.controls(last, setFrame, () => state.frame);
  setFrame(0);
})();
