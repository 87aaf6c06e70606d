// selfrepair mission viewer. Draws the payload that selfrepair.experiment.viewer built: every
// pose, heading, segment and fault set comes from the data; this script only draws and navigates.
(function () {
  "use strict";

  const { CELL, data, svg, html, centre } = viewer;
  const frames = data.frames;
  const steps = data.steps;
  const repairs = data.repairs;
  const last = frames.length - 1;
  const LETTERS = { replacement: "R", lookahead: "L", replan: "P", "plan-repair": "A" };

  const state = { frame: -1, shown: 0, picked: null };

  // --- small helpers ----------------------------------------------------------------------------

  function poseText(pose) {
    return pose.x + "," + pose.y + "," + pose.heading;
  }

  function faultText(list) {
    return list.length ? list.join(", ") : "none";
  }

  function colour(source) {
    return data.colours[source] || "#555555";
  }

  // --- the map ----------------------------------------------------------------------------------

  // Drawing order: the initial plan lies above the executed path and the repair sites, so it
  // is never hidden under them.
  const layers = viewer.drawMaze(data.maze,
    ["blocked", "tolerance", "highlight", "executed", "repairs", "plan", "ends", "robot"]);

  function segmentPath(seg) {
    const a = centre(seg.from.x) + " " + centre(seg.from.y);
    const b = centre(seg.to.x) + " " + centre(seg.to.y);
    if (seg.via) return "M" + a + "Q" + centre(seg.via[0]) + " " + centre(seg.via[1]) + " " + b;
    return "M" + a + "L" + b;
  }

  function drawSegment(seg, stroke, lineWidth, parent, dashed) {
    const x = centre(seg.from.x);
    const y = centre(seg.from.y);
    if (seg.kind === "failed") {
      const g = svg("g", { stroke: stroke, "stroke-width": 0.22 * CELL }, parent);
      const d = 0.3 * CELL;
      svg("line", { x1: x - d, y1: y - d, x2: x + d, y2: y + d }, g);
      svg("line", { x1: x - d, y1: y + d, x2: x + d, y2: y - d }, g);
      return g;
    }
    if (seg.kind === "turn" || seg.kind === "wait") {
      const attrs = { cx: x, cy: y, r: 0.2 * CELL, fill: dashed ? "none" : stroke };
      if (dashed) Object.assign(attrs, { stroke: stroke, "stroke-width": 0.08 * CELL });
      return svg("circle", attrs, parent);
    }
    const attrs = {
      d: segmentPath(seg),
      fill: "none",
      stroke: stroke,
      "stroke-width": lineWidth,
      "stroke-linecap": "round",
    };
    if (dashed) attrs["stroke-dasharray"] = 0.35 * CELL + " " + 0.25 * CELL;
    return svg("path", attrs, parent);
  }

  // The initial plan: a thin dashed black line on a white halo, drawn above the executed path,
  // so it is never hidden and stands out on any step colour.
  const halo = svg("g", { id: "plan-halo", opacity: 0.85 }, layers.plan);
  const dashes = svg("g", { id: "plan-dashes" }, layers.plan);
  for (const seg of data.plan) {
    drawSegment(seg, "#ffffff", 0.26 * CELL, halo, false);
    drawSegment(seg, "#111111", 0.12 * CELL, dashes, true);
  }

  // Plan tolerance (when the payload has it): the share of the fault model's sets that,
  // appearing before a step of the initial plan, force a replan, as a heat colour (white: every
  // set covered; from a light tint for one set to vermillion for all, by the square root of the
  // share so that a few uncovered sets show). On the map each plan cell shows its worst step;
  // the strip under the map shows every step.
  const tolerance = data.tolerance;

  function heat(share) {
    const t = share > 0 ? 0.25 + 0.75 * Math.sqrt(share) : 0;
    const mix = (a, b) => Math.round(a + (b - a) * t);
    return "rgb(" + mix(255, 213) + "," + mix(255, 94) + "," + mix(255, 0) + ")";
  }

  function toleranceText(s, n) {
    const here = s.needs_replan.length ? "; needs a replan here under " + s.needs_replan.join("; ")
      : "";
    return "plan step " + s.step + " (" + s.pose.join(",") + ", " + s.action + "): " +
      s.uncovered.length + " of " + n + " fault sets uncovered" + here;
  }

  function buildTolerance() {
    if (!tolerance) return;
    const n = tolerance.fault_sets.length;
    const worst = new Map();
    for (const s of tolerance.steps) {
      const key = s.pose[0] + "," + s.pose[1];
      if (!worst.has(key) || worst.get(key).uncovered.length < s.uncovered.length) worst.set(key, s);
    }
    for (const s of worst.values()) {
      const cell = svg("rect", {
        x: s.pose[0] * CELL, y: s.pose[1] * CELL, width: CELL, height: CELL,
        fill: heat(s.uncovered.length / n), "data-step": s.step,
      }, layers.tolerance);
      svg("title", {}, cell).textContent = toleranceText(s, n);
    }
    // Where a step itself needs a replan under some fault set: a dark frame on its cell.
    for (const s of tolerance.steps.filter((t) => t.needs_replan.length)) {
      svg("rect", {
        x: (s.pose[0] + 0.08) * CELL, y: (s.pose[1] + 0.08) * CELL, width: 0.84 * CELL,
        height: 0.84 * CELL, fill: "none", stroke: "#7a2900", "stroke-width": 0.12 * CELL,
        "data-needs": s.step,
      }, layers.tolerance);
    }
    document.getElementById("tolerance").hidden = false;
    const pct = (100 * tolerance.share).toFixed(1);
    document.getElementById("tolerance-title").textContent = "Plan tolerance (" +
      tolerance.model + ", " + n + " fault sets): " + tolerance.covered + " of " +
      tolerance.pairs + " (step, fault set) pairs covered (" + pct + "%), tolerant: " +
      (tolerance.tolerant ? "yes" : "no");
    const strip = document.getElementById("tolerance-strip");
    const count = Math.max(tolerance.steps.length, 1);
    const w = (TL.right - TL.left) / count;
    for (const s of tolerance.steps) {
      const rect = svg("rect", {
        x: TL.left + s.step * w, y: 4, width: Math.max(w, 0.5), height: 18,
        fill: heat(s.uncovered.length / n), stroke: "#d8d8dc", "stroke-width": 0.3,
        "data-step": s.step, "data-uncovered": s.uncovered.length,
      }, strip);
      svg("title", {}, rect).textContent = toleranceText(s, n);
      if (s.needs_replan.length) {
        svg("rect", {
          x: TL.left + s.step * w, y: 24, width: Math.max(w, 0.5), height: 5, fill: "#7a2900",
          "data-needs": s.needs_replan.length,
        }, strip);
      }
    }
    svg("text", { x: 4, y: 17, "font-size": 11, fill: "#6b6b70" }, strip).textContent =
      "plan step";
    svg("text", { x: 4, y: 30, "font-size": 9, fill: "#6b6b70" }, strip).textContent =
      "replan here";
    svg("text", { x: TL.right, y: 36, "font-size": 10, "text-anchor": "end", fill: "#6b6b70" },
      strip).textContent = "step " + tolerance.steps.length;
  }

  // The executed steps, coloured by source, shown up to the current frame.
  const executed = steps.map((seg) => {
    const node = drawSegment(seg, colour(seg.source), 0.45 * CELL, layers.executed, false);
    node.setAttribute("data-step", seg.step);
    node.setAttribute("display", "none");
    return node;
  });

  // Repair sites: a lettered ring where the robot stood when it repaired.
  const markers = repairs.map((r) => {
    const g = svg("g", { class: "repair-marker", "data-repair": r.index, display: "none" },
      layers.repairs);
    svg("circle", {
      cx: centre(r.pose.x), cy: centre(r.pose.y), r: 0.36 * CELL, fill: "#ffffff",
      "fill-opacity": 0.7, stroke: colour(r.source), "stroke-width": 0.1 * CELL,
    }, g);
    const text = svg("text", {
      x: centre(r.pose.x), y: centre(r.pose.y) + 0.17 * CELL, "text-anchor": "middle",
      "font-size": 0.48 * CELL, "font-weight": 700, fill: colour(r.source),
    }, g);
    text.textContent = LETTERS[r.source] || "?";
    svg("title", {}, g).textContent = "repair " + (r.index + 1) + ": " + r.how;
    g.addEventListener("click", () => pickRepair(r.index));
    return g;
  });

  // Start and goal.
  svg("circle", {
    cx: centre(data.start.x), cy: centre(data.start.y), r: 0.3 * CELL, fill: "#111111",
  }, layers.ends);
  const gx = centre(data.goal[0]);
  const gy = centre(data.goal[1]);
  const star = [];
  for (let i = 0; i < 10; i += 1) {
    const radius = (i % 2 ? 0.2 : 0.48) * CELL;
    const a = (Math.PI / 5) * i - Math.PI / 2;
    star.push((gx + radius * Math.cos(a)).toFixed(2) + "," + (gy + radius * Math.sin(a)).toFixed(2));
  }
  svg("polygon", {
    points: star.join(" "), fill: "#F0E442", stroke: "#111111", "stroke-width": 0.06 * CELL,
  }, layers.ends);

  // The robot: a triangle pointing north, turned by the heading angle of the data.
  const robot = svg("g", { id: "robot" }, layers.robot);
  svg("polygon", {
    points: [0, -0.45 * CELL, 0.34 * CELL, 0.32 * CELL, -0.34 * CELL, 0.32 * CELL].join(" "),
    fill: "#D55E00", stroke: "#111111", "stroke-width": 0.07 * CELL,
  }, robot);

  // --- the fault timeline -----------------------------------------------------------------------

  const timeline = document.getElementById("timeline");
  const rows = data.fault_timeline;
  const TL = { left: 70, right: 990, row: 22, top: 6 };
  const tlHeight = TL.top + Math.max(rows.length, 1) * TL.row + 26;
  timeline.setAttribute("viewBox", "0 0 1000 " + tlHeight);

  function tlX(frame) {
    return TL.left + (last ? frame / last : 0) * (TL.right - TL.left);
  }

  rows.forEach((row, i) => {
    const y = TL.top + i * TL.row;
    svg("text", { x: 4, y: y + 13, "font-size": 12 }, timeline).textContent = row.fault;
    for (const run of row.active) {
      svg("rect", {
        x: tlX(run[0]), y: y + 2, width: Math.max(tlX(run[1]) - tlX(run[0]), 1.5), height: 8,
        fill: "#D55E00", "data-fault": row.fault, "data-kind": "true",
      }, timeline);
    }
    for (const run of row.known) {
      svg("rect", {
        x: tlX(run[0]), y: y + 11, width: Math.max(tlX(run[1]) - tlX(run[0]), 1.5), height: 6,
        fill: "#0072B2", "data-fault": row.fault, "data-kind": "known",
      }, timeline);
    }
  });
  if (!rows.length) {
    svg("text", { x: 4, y: TL.top + 13, "font-size": 12, fill: "#6b6b70" }, timeline)
      .textContent = "no faults during this mission";
  }
  const axisY = TL.top + Math.max(rows.length, 1) * TL.row + 4;
  svg("line", { x1: TL.left, y1: axisY, x2: TL.right, y2: axisY, stroke: "#999999" }, timeline);
  for (const r of repairs) {
    svg("line", {
      x1: tlX(r.step), y1: axisY, x2: tlX(r.step), y2: axisY + 10, stroke: colour(r.source),
      "stroke-width": 2,
    }, timeline);
  }
  svg("text", { x: 4, y: axisY + 10, "font-size": 10, fill: "#6b6b70" }, timeline)
    .textContent = "repairs";
  svg("text", { x: TL.right, y: axisY + 21, "font-size": 10, "text-anchor": "end",
    fill: "#6b6b70" }, timeline).textContent = "step " + last;
  const cursor = svg("line", {
    x1: TL.left, y1: 0, x2: TL.left, y2: axisY + 12, stroke: "#111111", "stroke-width": 1.5,
  }, timeline);
  timeline.addEventListener("click", (event) => {
    const box = timeline.getBoundingClientRect();
    const x = ((event.clientX - box.left) / box.width) * 1000;
    const share = (x - TL.left) / (TL.right - TL.left);
    nav.jump(Math.min(Math.max(share, 0), 1) * last);
  });

  // --- the side panel ---------------------------------------------------------------------------

  function describeOrigin() {
    const origin = data.origin;
    const line = document.getElementById("origin");
    if (origin.kind === "results") {
      line.textContent = "Mission " + origin.key.slice(0, 12) + " of experiment " +
        origin.experiment + " in " + origin.source + ", run again from its stored configuration.";
    } else {
      line.textContent = "Trace " + origin.source + ".";
    }
    line.textContent += " Fault schedule: " + data.schedule + ".";
    const warnings = [];
    if (origin.kind === "results" && !origin.agrees) {
      warnings.push("The re-run differs from the stored row (stored: " + origin.stored.status +
        ", " + origin.stored.steps + " steps); the results came from another version.");
    }
    if (!data.has_repair_lines) {
      warnings.push("This trace has no repair lines (written before they existed): the " +
        "repairs' sources and latencies are not known.");
    }
    if (warnings.length) {
      const box = document.getElementById("warning");
      box.textContent = warnings.join(" ");
      box.hidden = false;
    }
  }

  function buildLegend() {
    const legend = document.getElementById("legend");
    function toggle(label, layer, swatch) {
      const item = html("label", null, null, legend);
      const box = html("input", null, null, item);
      box.type = "checkbox";
      box.checked = true;
      box.addEventListener("change", () => {
        layer.setAttribute("display", box.checked ? "inline" : "none");
      });
      item.appendChild(swatch);
      html("span", label, null, item);
    }
    toggle("initial plan", layers.plan, html("span", null, "swatch dashed"));
    const exec = html("span", null, "swatch");
    exec.style.background = "linear-gradient(90deg," + ["plan", "replacement", "lookahead",
      "replan"].map(colour).join(",") + ")";
    toggle("executed path", layers.executed, exec);
    const ring = html("span", "R L P", null);
    toggle("repair sites", layers.repairs, ring);
    if (tolerance) {
      const sw = html("span", null, "swatch");
      sw.style.background = "linear-gradient(90deg," + heat(0) + "," + heat(1) + ")";
      toggle("plan tolerance", layers.tolerance, sw);
    }
    for (const source of Object.keys(data.colours)) {
      const item = html("span", null, null, legend);
      const sw = html("span", null, "swatch", item);
      sw.style.background = colour(source);
      html("span", " " + source, null, item);
    }
  }

  function buildRepairList() {
    const list = document.getElementById("repairs");
    document.getElementById("repair-count").textContent = "(" + repairs.length + ")";
    for (const r of repairs) {
      const item = html("li", null, null, list);
      item.setAttribute("data-repair", r.index);
      const tag = html("span", r.source_name, "tag", item);
      tag.style.background = colour(r.source);
      html("span", " step " + r.step + ": " + r.how + ", " + r.latency +
        (r.status === "repaired" ? "" : " (" + r.status + ")"), null, item);
      item.addEventListener("click", () => pickRepair(r.index));
    }
    if (!repairs.length) html("li", "no repairs", "none", list);
  }

  function repairCard(r, parent) {
    const card = html("div", null, "repair-card", parent);
    card.style.borderLeftColor = colour(r.source);
    const head = html("div", null, null, card);
    const tag = html("span", r.source_name, "tag", head);
    tag.style.background = colour(r.source);
    html("span", " " + r.status + " in " + r.latency, null, head);
    const facts = [
      ["source", r.how],
      ["faulty action", r.action === null ? "none (plan ran out)" : r.action],
      ["at pose", poseText(r.pose)],
      ["known faults", faultText(r.known)],
      ["tried", r.attempts.join(" then ")],
      ["dropped", r.consumed + " queued action" + (r.consumed === 1 ? "" : "s")],
      ["spliced in", r.actions.length ? r.actions.join(" ") : "nothing"],
      ["executed as steps", r.executed.length ? r.executed.join(", ") : "none"],
    ];
    for (const [name, value] of facts) {
      const line = html("div", null, "detail", card);
      html("span", name + ": ", null, line);
      html("code", value, null, line);
    }
  }

  const eventItems = [];
  function buildEvents() {
    const list = document.getElementById("events");
    for (const e of data.fault_events) {
      const item = html("li", "step " + e.frame + ": " + e.fault + " " + e.kind, null, list);
      eventItems.push([e.frame, item]);
    }
    if (!data.fault_events.length) html("li", "no fault events", "none", list);
  }

  function updateNow(k) {
    const frame = frames[k];
    const now = document.getElementById("now");
    now.textContent = "";
    const facts = [
      ["step", k + " of " + last],
      ["tick", frame.tick],
      ["pose", poseText(frame.pose)],
    ];
    if (k > 0) {
      const s = steps[k - 1];
      facts.push(["last action", s.action + " (" + s.source + ", " + s.duration + " ticks)"]);
    }
    if (k < last) {
      facts.push(["next action", steps[k].action + " (" + steps[k].source + ")"]);
    } else {
      facts.push(["outcome", data.status]);
    }
    facts.push(["true faults", faultText(frame.true)]);
    facts.push(["known faults", faultText(frame.known)]);
    for (const [name, value] of facts) {
      html("dt", name, null, now);
      html("dd", value, null, now).setAttribute("data-fact", name);
    }
  }

  function updateFaults(k) {
    const body = document.querySelector("#faults tbody");
    body.textContent = "";
    const frame = frames[k];
    const fresh = new Set(data.fault_events.filter((e) => e.frame === k).map((e) => e.fault));
    for (const row of rows) {
      const tr = html("tr", null, fresh.has(row.fault) ? "fresh" : null, body);
      html("td", row.fault, null, tr);
      const isTrue = frame.true.includes(row.fault);
      const isKnown = frame.known.includes(row.fault);
      html("td", isTrue ? "yes" : "no", isTrue ? "yes true" : null, tr);
      html("td", isKnown ? "yes" : "no", isKnown ? "yes known" : null, tr);
    }
    if (!rows.length) {
      const tr = html("tr", null, null, body);
      html("td", "no faults", "none", tr).colSpan = 3;
    }
  }

  function updateRepairs(k, selected) {
    const here = document.getElementById("repairs-now");
    here.textContent = "";
    const now = repairs.filter((r) => r.step === k);
    for (const r of now) repairCard(r, here);
    if (!now.length) html("p", "none", "none", here);
    for (const item of document.querySelectorAll("#repairs li[data-repair]")) {
      const index = Number(item.getAttribute("data-repair"));
      item.classList.toggle("future", repairs[index].step > k);
      item.classList.toggle("selected", index === selected);
    }
    markers.forEach((m, i) => m.setAttribute("display", repairs[i].step <= k ? "inline" : "none"));
  }

  function highlight(selected) {
    layers.highlight.textContent = "";
    if (selected === null) return;
    const r = repairs[selected];
    for (const seg of r.path) {
      drawSegment(seg, "#F0E442", 0.85 * CELL, layers.highlight, false)
        .setAttribute("opacity", "0.8");
    }
    svg("circle", {
      cx: centre(r.pose.x), cy: centre(r.pose.y), r: 0.6 * CELL, fill: "none",
      stroke: "#F0E442", "stroke-width": 0.2 * CELL,
    }, layers.highlight);
  }

  // The repair to highlight at frame k: the one picked in the list while still at its step,
  // else the latest repair made at or before k.
  function selectedAt(k) {
    if (state.picked !== null && repairs[state.picked].step === k) return state.picked;
    let chosen = null;
    for (const r of repairs) {
      if (r.step > k) break;
      chosen = r.index;
    }
    return chosen;
  }

  // --- navigation -------------------------------------------------------------------------------

  const slider = document.getElementById("slider");
  const label = document.getElementById("step-label");

  function setFrame(k) {
    k = Math.min(Math.max(Math.round(k), 0), last);
    if (k === state.frame) return;
    for (let i = state.shown; i < k; i += 1) executed[i].setAttribute("display", "inline");
    for (let i = k; i < state.shown; i += 1) executed[i].setAttribute("display", "none");
    state.shown = k;
    state.frame = k;
    const pose = frames[k].pose;
    viewer.placeRobot(robot, pose, k);
    viewer.drawBlocked(layers.blocked, frames[k].blocked || []);
    slider.value = String(k);
    label.textContent = "step " + k + " / " + last + " \u00b7 " + poseText(pose);
    const x = tlX(k);
    cursor.setAttribute("x1", x);
    cursor.setAttribute("x2", x);
    const selected = selectedAt(k);
    highlight(selected);
    updateNow(k);
    updateFaults(k);
    diagnosisView.update(k);
    updateRepairs(k, selected);
    for (const [frame, item] of eventItems) {
      item.classList.toggle("future", frame > k);
      item.classList.toggle("now", frame === k);
    }
  }

  function pickRepair(index) {
    nav.stop();
    state.picked = index;
    state.frame = -1; // redraw even when already at that step
    setFrame(repairs[index].step);
  }

  const nav = viewer.controls(last, setFrame, () => state.frame);

  describeOrigin();
  buildTolerance();
  buildLegend();
  buildRepairList();
  buildEvents();
  viewer.buildSummary(data.summary);
  setFrame(0);
})();
