// selfrepair mission viewer, the diagnosis panel (faults hidden; payload "diagnosis", built by
// selfrepair.experiment.viewdiagnosis): per step, the hypotheses and classes still possible, the
// most probable class and the surprises. A strip draws the hypotheses left after each step (bar
// height: their share, on a log scale) with each surprise marked; the facts follow the frame.
// It runs before viewer.js, which calls diagnosisView.update(k) on every frame.
const diagnosisView = (function () {
  "use strict";

  const { data, svg, html } = viewer;
  const d = data.diagnosis;
  if (!d) return { update() {} };
  document.getElementById("diagnosis").hidden = false;
  const frames = d.frames;
  const steps = Math.max(frames.length - 1, 1);
  const width = 1000 / steps;
  const strip = document.getElementById("belief-strip");
  const top = Math.log2(Math.max(d.hypotheses, 2));
  document.getElementById("diagnosis-title").textContent = "Diagnosis (" + d.hypotheses +
    " hypotheses, " + d.classes + " classes)";
  for (let k = 1; k < frames.length; k += 1) {
    const f = frames[k];
    const x = (k - 1) * width;
    if (f.alive !== null) {
      const h = 4 + 46 * Math.log2(Math.max(f.alive, 1)) / top;
      const bar = svg("rect", {
        x: x, y: 50 - h, width: Math.max(width - 0.5, 0.5), height: h, fill: "#56B4E9",
        "data-alive": f.alive, "data-step": k - 1,
      }, strip);
      svg("title", {}, bar).textContent = "after step " + (k - 1) + ": " + f.alive +
        " hypotheses, " + f.classes + " classes";
    }
    if (f.surprise) {
      const mark = svg("polygon", {
        points: [x, 60, x + width, 60, x + width / 2, 52].join(" "), fill: "#D55E00",
        "data-surprise": k - 1,
      }, strip);
      svg("title", {}, mark).textContent = "surprise at step " + (k - 1);
    }
  }
  const cursor = svg("line", { y1: 0, y2: 60, stroke: "#000", "stroke-width": 2 }, strip);

  function update(k) {
    const f = frames[k];
    const now = document.getElementById("belief-now");
    now.textContent = "";
    const facts = [];
    if (d.believes) {
      facts.push(["hypotheses left", f.alive === null ? "-" : f.alive + " of " + d.hypotheses]);
      facts.push(["classes left", f.classes === null ? "-" : f.classes + " of " + d.classes]);
      facts.push(["most probable", f.best === null ? "-" : f.best]);
    }
    facts.push(["surprise", k === 0 ? "-" : (f.surprise ? "yes" : "no")]);
    facts.push(["readings", String(f.readings)]);
    for (const [name, value] of facts) {
      html("dt", name, null, now);
      html("dd", value, f.surprise && name === "surprise" ? "surprise" : null, now)
        .setAttribute("data-fact", name);
    }
    const x = Math.max(k - 0.5, 0) * width;
    cursor.setAttribute("x1", x);
    cursor.setAttribute("x2", x);
  }

  return { update };
})();
