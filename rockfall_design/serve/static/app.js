// rockfall-design serve: the page. Plain JavaScript and SVG, no library, no network
// beyond this app's own API. The token the server wrote into the page goes with every
// request in a header (no cookie: a cookie of 127.0.0.1 would go to every port of it).
"use strict";

const SVG = "http://www.w3.org/2000/svg";
const $ = (id) => document.getElementById(id);
const MATERIAL_COLOURS = ["#8d6e63", "#c2a36b", "#7cb342", "#90a4ae", "#b0876b", "#5d8aa8",
  "#d4a373", "#6d9886"];
const W = 900;                      // drawing width (SVG units = px at 100 %)
const PAD = { l: 48, r: 12, t: 12, b: 26 };

const TOKEN = document.querySelector("meta[name='rockfall-token']").content;
const state = {
  projects: [], project: null, plugins: null, run: null, job: null,
  placed: null,                     // {type, params, x}
  chosen: null,                     // the optimiser's chosen measures
  inflight: false, pendingX: null, lastResult: null, lastMs: null,
  sx: null,                         // x scale of every drawing: m -> px
};

// ---- helpers --------------------------------------------------------------------
async function api(path, body) {
  const headers = { "X-Rockfall-Token": TOKEN };
  const opts = body === undefined ? { headers } : {
    method: "POST", headers: { ...headers, "Content-Type": "application/json" },
    body: JSON.stringify(body),
  };
  const resp = await fetch(path, opts);
  let data = null;
  try { data = await resp.json(); } catch (e) { data = { error: resp.statusText }; }
  if (!resp.ok) throw new Error(data && data.error ? data.error : resp.statusText);
  return data;
}
function el(tag, attrs, parent) {
  const e = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}
function clear(svg) { while (svg.firstChild) svg.removeChild(svg.firstChild); }
function fmt(v, d = 2) { return v === null || v === undefined ? "–" : Number(v).toFixed(d); }
function pct(v) { return (100 * v).toPrecision(2) + " %"; }
function showError(msg) { $("error").textContent = msg || ""; }
function groundAt(x) {
  const g = state.project.ground;
  if (x <= g[0][0]) return g[0][1];
  for (let i = 1; i < g.length; i++) {
    if (x <= g[i][0]) {
      const t = (x - g[i - 1][0]) / (g[i][0] - g[i - 1][0]);
      return g[i - 1][1] + t * (g[i][1] - g[i - 1][1]);
    }
  }
  return g[g.length - 1][1];
}

// ---- the section, to scale ---------------------------------------------------------
function drawSection() {
  const p = state.project, svg = $("section");
  clear(svg);
  const xs = p.ground.map((q) => q[0]), ys = p.ground.map((q) => q[1]);
  const x0 = Math.min(...xs), x1 = Math.max(...xs);
  const y0 = Math.min(...ys) - 5, y1 = Math.max(...ys) + 15;
  // One scale for x and y: the section to scale.
  const k = Math.min((W - PAD.l - PAD.r) / (x1 - x0), 520 / (y1 - y0));
  const H = Math.ceil((y1 - y0) * k) + PAD.t + PAD.b;
  svg.setAttribute("viewBox", `0 0 ${W} ${H}`);
  const X = (x) => PAD.l + (x - x0) * k, Y = (y) => PAD.t + (y1 - y) * k;
  state.sx = { x0, x1, k, X, Y, H, inv: (px) => x0 + (px - PAD.l) / k };
  // ground: filled below, each segment in its material's colour
  const fill = p.ground.map((q) => `${X(q[0])},${Y(q[1])}`).join(" ");
  el("polygon", { points: `${X(x0)},${Y(y0)} ${fill} ${X(x1)},${Y(y0)}`, fill: "#eceae4" }, svg);
  const names = [...new Set(p.materials)];
  for (let i = 1; i < p.ground.length; i++) {
    const c = MATERIAL_COLOURS[names.indexOf(p.materials[i - 1]) % MATERIAL_COLOURS.length];
    el("line", { x1: X(p.ground[i - 1][0]), y1: Y(p.ground[i - 1][1]), x2: X(p.ground[i][0]),
      y2: Y(p.ground[i][1]), stroke: c, "stroke-width": 4, "data-material": p.materials[i - 1] },
      svg);
  }
  // axes: x along the bottom, elevation on the left
  for (let x = Math.ceil(x0 / 50) * 50; x <= x1; x += 50) {
    el("line", { x1: X(x), y1: H - PAD.b, x2: X(x), y2: H - PAD.b + 4, stroke: "#555" }, svg);
    el("text", { x: X(x), y: H - 8, "text-anchor": "middle" }, svg).textContent = `${x} m`;
  }
  for (let y = Math.ceil(y0 / 50) * 50; y <= y1; y += 50) {
    el("text", { x: 4, y: Y(y) + 4 }, svg).textContent = `${y}`;
  }
  // protected zone
  if (p.protect) {
    el("rect", { x: X(p.protect.x), y: PAD.t, width: Math.max(2, X(x1) - X(p.protect.x)),
      height: H - PAD.t - PAD.b, fill: "rgba(220,40,40,0.12)", id: "protect-zone" }, svg);
    el("text", { x: X(p.protect.x) + 3, y: PAD.t + 12, fill: "#a11" }, svg).textContent =
      `protected zone x ≥ ${p.protect.x} m`;
  }
  // release zones
  for (const r of p.releases) {
    const [a, b] = r.x;
    const pts = [];
    for (let x = a; x <= b + 1e-9; x += Math.max((b - a) / 10, 0.1)) pts.push(`${X(x)},${Y(groundAt(x)) - 5}`);
    el("polyline", { points: pts.join(" "), fill: "none", stroke: "#f57c00", "stroke-width": 5,
      class: "release" }, svg);
  }
  // stations
  for (const s of p.stations) {
    el("line", { x1: X(s), y1: Y(groundAt(s)), x2: X(s), y2: Y(groundAt(s)) - 30,
      stroke: "#1565c0", "stroke-dasharray": "3,2" }, svg);
    el("text", { x: X(s), y: Y(groundAt(s)) - 33, "text-anchor": "middle", fill: "#1565c0" },
      svg).textContent = `${s}`;
  }
  // the project's own measures
  for (const m of p.measures) drawMeasure(svg, m, "#555", false);
  // the run: rock paths and where they stop
  if (state.run) {
    const g = el("g", { id: "paths", opacity: 0.55 }, svg);
    for (const path of state.run.paths) {
      el("polyline", { points: path.map((q) => `${X(q[0])},${Y(q[1])}`).join(" "), fill: "none",
        stroke: "#6a1b9a", "stroke-width": 0.8 }, g);
    }
    const s = state.run.stops;
    for (let i = 0; i < s.counts.length; i++) {
      if (!s.counts[i]) continue;
      const xm = 0.5 * (s.edges[i] + s.edges[i + 1]);
      el("circle", { cx: X(xm), cy: Y(groundAt(xm)) - 2, r: Math.min(6, 1 + Math.log10(1 + s.counts[i]) * 1.6),
        fill: "#00897b", opacity: 0.7 }, svg);
    }
  }
  for (const m of state.chosen || []) drawMeasure(svg, m, "#2e7d32", false);
  if (state.placed) drawMeasure(svg, { ...state.placed.params, type: state.placed.type, x: state.placed.x },
    "#c62828", true);
  svg.onmousemove = (ev) => hover(ev);
  drawLegend(names);
}

function drawMeasure(svg, m, colour, draggable) {
  const { X, Y, k } = state.sx;
  const x = Number(m.x), g = groundAt(x);
  const h = Number(m.height || m.block_size || m.depth || 2);
  const grp = el("g", { class: draggable ? "placed" : "measure", id: draggable ? "placed" : "" }, svg);
  if (m.type === "ditch" || m.type === "berm") {
    const w = Number(m.width || 4);
    el("rect", { x: X(x), y: Y(g) - 3, width: w * k, height: 6, fill: colour, opacity: 0.6 }, grp);
  } else {
    el("line", { x1: X(x), y1: Y(g), x2: X(x), y2: Y(g + h), stroke: colour,
      "stroke-width": m.type === "wall" ? 4 : 2.5 }, grp);
  }
  const label = el("text", { x: X(x) + 4, y: Y(g + h) - 4, fill: colour }, grp);
  label.textContent = draggable ? `${m.type} ${fmt(x, 1)} m` : (m.label || `${m.type} ${fmt(x, 1)} m`);
  const tip = el("title", {}, grp);
  tip.textContent = m.label || `${m.type} at x = ${fmt(x, 1)} m`;
  if (draggable) {
    // A wide, invisible grip: easy to catch with the mouse.
    const grip = el("rect", { x: X(x) - 9, y: Y(g + h) - 14, width: 18, height: Y(g) - Y(g + h) + 20,
      fill: "rgba(198,40,40,0.15)", class: "handle", id: "placed-handle" }, grp);
    grip.addEventListener("pointerdown", startDrag);
  }
}

function drawLegend(names) {
  // Built node by node: names come from the project file, never parsed as HTML.
  const items = names.map((n, i) => [MATERIAL_COLOURS[i % MATERIAL_COLOURS.length], n]);
  items.push(["#f57c00", "release zone"], ["#1565c0", "station"], ["rgba(220,40,40,0.3)", "protected zone"]);
  if (state.run) items.push(["#6a1b9a", "rock paths"], ["#00897b", "stops"]);
  const legend = $("legend");
  legend.textContent = "";
  for (const [colour, name] of items) {
    const span = document.createElement("span"), swatch = document.createElement("i");
    swatch.style.background = colour;
    span.append(swatch, name);
    legend.appendChild(span);
  }
}

// ---- envelopes and stops ------------------------------------------------------------
// A round step (1, 2 or 5 times a power of ten) giving about n intervals over range.
function niceStep(range, n) {
  if (!(range > 0)) return 1;
  const raw = range / n, p = 10 ** Math.floor(Math.log10(raw)), f = raw / p;
  const step = (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * p;
  // Never fewer than two intervals (three ticks): rounding 2.01 up to 5 would show 9.5
  // rocks as 0 and 5 only. Only that jump can do it: the others at most halve n.
  return range / step < 2 ? 2 * p : step;
}
function tickText(v, step) {
  const d = step >= 1 ? 0 : Math.min(6, Math.ceil(-Math.log10(step)));
  return Number(v).toFixed(d);
}

// A chart along the section: x in m on the section's own scale, both axes with ticks and
// titles, and a legend that keys every series by its colour.
function drawChart(svg, xs, series, ytitle, marker) {
  clear(svg);
  const { X, x0, x1 } = state.sx, H = 190, B = 40;       // B: room for x ticks and title
  svg.setAttribute("viewBox", `0 0 ${W} ${H}`);
  let ymax = 0;
  for (const s of series) for (const v of s.values) if (v !== null && v > ymax) ymax = v;
  ymax = ymax > 0 ? ymax * 1.05 : 1;
  const top = PAD.t + 16;                                // room for the legend
  const Y = (v) => H - B - (v / ymax) * (H - top - B);
  const axes = el("g", { class: "axes" }, svg);
  el("line", { x1: PAD.l, y1: H - B, x2: W - PAD.r, y2: H - B, stroke: "#999", class: "x-axis" }, axes);
  el("line", { x1: PAD.l, y1: top, x2: PAD.l, y2: H - B, stroke: "#999", class: "y-axis" }, axes);
  const ys = niceStep(ymax, 4);
  for (let v = 0; v <= ymax + 1e-9; v += ys) {
    const g = el("g", { class: "y-tick" }, axes);
    el("line", { x1: PAD.l - 4, y1: Y(v), x2: PAD.l, y2: Y(v), stroke: "#555" }, g);
    el("line", { x1: PAD.l, y1: Y(v), x2: W - PAD.r, y2: Y(v), stroke: "#eee" }, g);
    el("text", { x: PAD.l - 6, y: Y(v) + 4, "text-anchor": "end" }, g).textContent = tickText(v, ys);
  }
  const xstep = niceStep(x1 - x0, 8);
  for (let x = Math.ceil(x0 / xstep) * xstep; x <= x1 + 1e-9; x += xstep) {
    const g = el("g", { class: "x-tick" }, axes);
    el("line", { x1: X(x), y1: H - B, x2: X(x), y2: H - B + 4, stroke: "#555" }, g);
    el("text", { x: X(x), y: H - B + 16, "text-anchor": "middle" }, g).textContent = tickText(x, xstep);
  }
  el("text", { x: (PAD.l + W - PAD.r) / 2, y: H - 4, "text-anchor": "middle", class: "axis-title x-title" },
    axes).textContent = "x along the section (m)";
  el("text", { x: 0, y: 0, "text-anchor": "middle", class: "axis-title y-title",
    transform: `translate(11,${(top + H - B) / 2}) rotate(-90)` }, axes).textContent = ytitle;
  for (const s of series) {
    if (s.bars) {
      for (let i = 0; i < s.values.length; i++) {
        if (!s.values[i]) continue;
        el("rect", { x: X(xs[i]), y: Y(s.values[i]), width: Math.max(1, X(xs[i + 1]) - X(xs[i]) - 0.5),
          height: H - B - Y(s.values[i]), fill: s.colour }, svg);
      }
      continue;
    }
    let d = "", pen = false;
    for (let i = 0; i < xs.length; i++) {
      const v = s.values[i];
      if (v === null) { pen = false; continue; }
      d += `${pen ? "L" : "M"}${X(xs[i]).toFixed(1)},${Y(v).toFixed(1)}`;
      pen = true;
    }
    el("path", { d, fill: "none", stroke: s.colour, "stroke-width": s.width || 1.5 }, svg);
  }
  // The legend: a colour swatch (a line, or a block for bars) before each series' name.
  const legend = el("g", { class: "chart-legend" }, svg);
  let lx = PAD.l + 8;
  for (const s of series) {
    const item = el("g", { class: "legend-item", "data-series": s.name }, legend);
    el("rect", s.bars ? { x: lx, y: PAD.t - 2, width: 12, height: 10, fill: s.colour, class: "legend-swatch" }
      : { x: lx, y: PAD.t + 2, width: 16, height: Math.max(2, s.width || 1.5) + 1, fill: s.colour,
        class: "legend-swatch" }, item);
    el("text", { x: lx + 20, y: PAD.t + 7 }, item).textContent = s.name;
    lx += 34 + 7 * s.name.length;
  }
  if (marker !== null && marker !== undefined) {
    el("line", { x1: X(marker), y1: top, x2: X(marker), y2: H - B, stroke: "#c62828",
      "stroke-dasharray": "4,3" }, svg);
  }
  svg.onmousemove = (ev) => hover(ev);
}

function drawRun() {
  const r = state.run, mark = state.placed ? state.placed.x : null;
  if (!r) { for (const id of ["env-height", "env-energy", "stops"]) clear($(id)); return; }
  const e = r.envelopes, colours = ["#90caf9", "#1565c0", "#0d47a1", "#7e57c2", "#26a69a", "#ef6c00"];
  const series = (q) => e.percentiles.map((p, i) => ({ name: p, values: q[p], colour: colours[i % colours.length] }))
    .concat([{ name: "max", values: q.max, colour: "#888", width: 1 }]);
  drawChart($("env-height"), e.x, series(e.height), "height (m)", mark);
  drawChart($("env-energy"), e.x, series(e.energy), "energy (kJ)", mark);
  drawChart($("stops"), r.stops.edges, [{ name: "stopped rocks", values: r.stops.counts, colour: "#00897b",
    bars: true }], "rocks per bin", mark);
}

function hover(ev) {
  if (!state.sx) return;
  const svg = ev.currentTarget, pt = svg.createSVGPoint();
  pt.x = ev.clientX; pt.y = ev.clientY;
  const p = pt.matrixTransform(svg.getScreenCTM().inverse());
  const x = state.sx.inv(p.x);
  if (x < state.sx.x0 || x > state.sx.x1) return;
  let text = `x = ${x.toFixed(1)} m, ground ${groundAt(x).toFixed(1)} m`;
  if (state.run) {
    const e = state.run.envelopes, j = Math.max(0, Math.min(e.x.length - 1, Math.round((x - e.x[0]) / (e.x[1] - e.x[0] || 1))));
    const hb = e.height_p95_bounds[j], eb = e.energy_p95_bounds[j], c = Math.round(100 * e.confidence);
    text += ` | passing ${e.crossings[j]} rocks, height p95 ${fmt(e.height.p95[j])} m` +
      ` [${fmt(hb[0])}, ${fmt(hb[1])}] (max ${fmt(e.height.max[j])}),` +
      ` energy p95 ${fmt(e.energy.p95[j], 0)} kJ [${fmt(eb[0], 0)}, ${fmt(eb[1], 0)}] (max ${fmt(e.energy.max[j], 0)});` +
      ` bounds at ${c} %`;
  }
  $("readout").textContent = text;
}

// ---- placing and dragging ----------------------------------------------------------
function measureParams() {
  const params = {};
  for (const input of $("measure-form").querySelectorAll("[name]")) {
    if (input.value === "") continue;
    const t = input.dataset.type || "";
    params[input.name] = t.includes("number") || t.includes("integer") ? Number(input.value) : input.value;
  }
  return params;
}

function buildForm() {
  const form = $("measure-form"), kind = $("measure-type").value;
  form.innerHTML = "";
  const m = state.plugins.measures.find((q) => q.kind === kind);
  if (!m) return;
  const defaults = { height: 5, capacity_kj: 2000 };
  for (const prm of m.parameters) {
    if (prm.name === "x") continue;
    const label = document.createElement("label");
    label.title = prm.description || "";
    label.textContent = `${prm.name}${prm.unit ? " (" + prm.unit + ")" : ""}${prm.required ? " *" : ""} `;
    let input;
    if (prm.options) {
      input = document.createElement("select");
      for (const o of prm.options) { const op = document.createElement("option"); op.value = o; op.textContent = o; input.appendChild(op); }
    } else {
      input = document.createElement("input");
      if (String(prm.type).includes("number") || String(prm.type).includes("integer")) {
        input.type = "number"; input.step = "any";
        if (prm.minimum !== null) input.min = prm.minimum;
        if (prm.maximum !== null) input.max = prm.maximum;
      }
      const d = prm.default !== null ? prm.default
        : (prm.design && prm.design.bounds ? prm.design.bounds[0] : defaults[prm.name]);
      if (d !== undefined && d !== null) input.value = d;
    }
    input.name = prm.name;
    input.dataset.type = prm.type;
    label.appendChild(input);
    form.appendChild(label);
  }
  form.onchange = () => { if (state.placed) { state.placed.params = measureParams(); requestPlace(state.placed.x); } };
}

function placeMeasure() {
  const p = state.project;
  const x = state.placed ? state.placed.x : Math.round(p.ground[0][0] + 0.45 * (p.ground[p.ground.length - 1][0] - p.ground[0][0]));
  state.placed = { type: $("measure-type").value, params: measureParams(), x };
  drawSection(); drawRun();
  requestPlace(x);
}

function startDrag(ev) {
  ev.preventDefault();
  const svg = $("section");
  const grip = ev.currentTarget;
  grip.setPointerCapture(ev.pointerId);
  const move = (e) => {
    const pt = svg.createSVGPoint(); pt.x = e.clientX; pt.y = e.clientY;
    const p = pt.matrixTransform(svg.getScreenCTM().inverse());
    // Half a metre inside either end: a measure on the end point is off the section.
    const x = Math.max(state.sx.x0 + 0.5, Math.min(state.sx.x1 - 0.5, state.sx.inv(p.x)));
    state.placed.x = Math.round(x * 2) / 2;
    moveMarker();
    requestPlace(state.placed.x);
  };
  const up = () => {
    grip.removeEventListener("pointermove", move);
    grip.removeEventListener("pointerup", up);
    drawSection(); drawRun();
  };
  grip.addEventListener("pointermove", move);
  grip.addEventListener("pointerup", up);
}

function moveMarker() {
  // Move the dragged measure without redrawing everything (the grip keeps the pointer).
  const { X, Y } = state.sx, m = state.placed, g = groundAt(m.x);
  const h = Number(m.params.height || m.params.block_size || 2);
  const grp = $("placed");
  if (!grp) return;
  const line = grp.querySelector("line"), text = grp.querySelector("text"), grip = $("placed-handle");
  const bed = grp.querySelector("rect:not(.handle)");
  if (bed) { bed.setAttribute("x", X(m.x)); bed.setAttribute("y", Y(g) - 3); }
  if (line) { line.setAttribute("x1", X(m.x)); line.setAttribute("x2", X(m.x)); line.setAttribute("y1", Y(g)); line.setAttribute("y2", Y(g + h)); }
  if (text) { text.setAttribute("x", X(m.x) + 4); text.setAttribute("y", Y(g + h) - 4); text.textContent = `${m.type} ${fmt(m.x, 1)} m`; }
  grip.setAttribute("x", X(m.x) - 9); grip.setAttribute("y", Y(g + h) - 14);
  grip.setAttribute("height", Y(g) - Y(g + h) + 20);
}

// The project's own measures (when ticked) as the project file gives them: without the
// label the app added for the drawing (not a parameter of the measure).
function ownMeasures() {
  if (!$("with-own").checked) return [];
  return state.project.measures.map(({ label, ...params }) => params);
}

// Latest wins: while a request is out, only the newest position waits for its turn.
function requestPlace(x) {
  if (state.inflight) { state.pendingX = x; return; }
  state.inflight = true;
  const t0 = performance.now();
  const m = state.placed;
  // The design on the section: the project's own measures (when asked) and the placed one.
  const own = ownMeasures();
  api("/api/place", { project: state.project.id, measures: [...own, { type: m.type, ...m.params, x }] })
    .then((r) => { state.lastMs = performance.now() - t0; showPlace(r); showError(""); })
    .catch((e) => { showError(e.message); $("residual").textContent = "—"; $("residual").className = "residual"; })
    .finally(() => {
      state.inflight = false;
      if (state.pendingX !== null) { const nx = state.pendingX; state.pendingX = null; requestPlace(nx); }
    });
}

// The verdict's state as a class of the page: green, red, or neither.
function verdictClass(state) {
  return state === "holds with confidence" ? "ok" : state === "fails" ? "fail" : "";
}

// A check's cell says what the verdict says: "untested" for a measure no rock met.
function checkWord(c, untested) {
  if (untested) return ["untested", "untested"];
  if (c.ok_with_confidence === null || c.ok_with_confidence === undefined)
    return c.ok ? ["holds", "ok"] : ["fails", "fail"];
  return c.ok_with_confidence ? ["holds", "ok"] : c.ok ? ["bound fails", ""] : ["fails", "fail"];
}

function showPlace(r) {
  state.lastResult = r;
  const res = r.residual, div = $("residual"), v = r.verdict;
  const untested = new Set(v.untested_measures);
  // The words are the verdict of check (judge.verdict) on these numbers.
  div.textContent = (res.protected_zone ? `At the protected zone (x ≥ ${res.x} m): `
    : `No protected zone (protect:); past the foot of the section (x = ${res.x} m): `) +
    `${res.reaching} of ${res.rocks} rocks ` +
    `(${pct(res.fraction)}, upper bound ${pct(res.upper_bound)} at ${Math.round(res.confidence * 100)} %); ` +
    `allowed ${pct(res.allowed_fraction)}. ` + v.headline +
    (r.approximate ? " (Rocks that break through keep their bare-slope paths here: Check this design decides.)" : "");
  div.className = "residual " + verdictClass(v.state);
  div.dataset.reaching = res.reaching;
  div.dataset.verdict = v.state;
  const body = $("checks").querySelector("tbody");
  body.innerHTML = "";
  for (const m of r.measures) {
    const head = document.createElement("tr"), td = document.createElement("td"), b = document.createElement("b");
    td.colSpan = 5;
    b.textContent = m.label;
    if (untested.has(m.label)) head.dataset.untested = "1";
    td.append(b, m.reshapes_ground ? ` (${r.rerun_rocks} rocks run again from above it)` : ` (table at ${m.x_table} m)`,
      untested.has(m.label) ? ": no rock reaches it, its checks say nothing" : "");
    head.appendChild(td);
    body.appendChild(head);
    for (const c of m.checks) {
      const tr = document.createElement("tr");
      tr.title = c.detail;
      const [word, cls] = checkWord(c, untested.has(m.label));
      const verdict = cell(word);
      verdict.className = cls;
      tr.append(cell(c.name), cell(fmt(c.value)), cell(fmt(c.bound)), cell(fmt(c.target)), verdict);
      body.appendChild(tr);
    }
  }
  const m0 = r.measures[r.measures.length - 1];
  $("counts").textContent = m0 ? `met ${m0.met}, caught ${m0.caught}, over ${m0.passed_over}, ` +
    `through ${m0.broken_through}` + (r.cost !== null ? `; cost ${Math.round(r.cost).toLocaleString()}` : "") : "";
  $("latency").textContent = `judged in ${fmt(r.elapsed_ms, 1)} ms on the server, ${fmt(state.lastMs, 0)} ms round trip`;
  $("latency").dataset.serverMs = r.elapsed_ms;
  $("latency").dataset.roundTripMs = state.lastMs;
}

// ---- runs: simulate, check, optimise --------------------------------------------------
function runOptions() {
  const body = {};
  if ($("rocks").value) body.rocks = Number($("rocks").value);
  if ($("seed").value) body.seed = Number($("seed").value);
  return body;
}

async function startJob(kind, body) {
  showError("");
  try {
    state.job = await api(`/api/projects/${state.project.id}/${kind}`, body);
  } catch (e) { showError(e.message); return; }
  for (const id of ["simulate", "check", "optimise", "study", "calibrate"]) $(id).disabled = true;
  $("cancel").disabled = false;
  $("status").dataset.state = "running";
  poll();
}

function simulate() { startJob("simulate", runOptions()); }

function checkDesign() {
  const measures = ownMeasures();
  if (state.placed) measures.push({ type: state.placed.type, ...state.placed.params, x: state.placed.x });
  startJob("check", { ...runOptions(), measures });
}

function optimiseDesign() { startJob("optimise", runOptions()); }
function studyProject() { startJob("study", runOptions()); }
// Calibrate with its own rocks (calibrate.rocks) unless the field was changed.
function calibrateProject() {
  const body = runOptions();
  if (body.rocks === state.project.rocks) delete body.rocks;
  startJob("calibrate", body);
}
function enableJobs() {
  const p = state.project;
  $("check").disabled = false; $("optimise").disabled = !p.has_design;
  $("study").disabled = !p.has_study; $("calibrate").disabled = !p.has_calibrate;
}

// A study's or calibration's tables, as they come (numbers to 4 significant digits).
function showTables(job) {
  const div = $("results");
  div.innerHTML = "";
  const head = document.createElement("p");
  head.textContent = `${job.kind} done in ${fmt(job.runtime_s, 1)} s`;
  div.appendChild(head);
  for (const t of job.tables) {
    const h = document.createElement("h4"); h.textContent = t.title; div.appendChild(h);
    const table = document.createElement("table");
    table.className = "job-table"; table.dataset.title = t.title;
    const hr = document.createElement("tr");
    for (const c of t.columns) { const th = document.createElement("th"); th.textContent = c; hr.appendChild(th); }
    table.appendChild(hr);
    for (const row of t.rows) {
      const tr = document.createElement("tr");
      for (const v of row) {
        tr.appendChild(cell(v === null ? "–" : typeof v === "number" ? Number(v.toPrecision(4)).toString()
          : typeof v === "object" ? JSON.stringify(v) : String(v)));
      }
      table.appendChild(tr);
    }
    div.appendChild(table);
  }
}

async function poll() {
  let job;
  try {
    job = await api(`/api/jobs/${state.job.id}`);
  } catch (e) {
    // The server may be busy for a moment: say so and ask again.
    showError(`progress: ${e.message}`);
    setTimeout(poll, 1000);
    return;
  }
  state.job = job;
  $("progress").max = job.total; $("progress").value = job.done;
  const what = job.kind !== "simulate" && job.kind !== "check" ? `${job.stage || "search"} ${job.done} of ${job.total}`
    : `${job.done} of ${job.total} rocks`;
  $("status").textContent = `${job.kind} ${job.state}: ${what} (${fmt(job.runtime_s, 1)} s)`;
  if (job.state === "running") { setTimeout(poll, 250); return; }
  $("cancel").disabled = true; $("simulate").disabled = false;
  enableJobs();
  if (job.state === "failed") showError(job.error);
  if (job.state !== "done") { $("status").dataset.state = job.state; return; }
  if (job.kind === "simulate") {
    state.run = await api(`/api/projects/${state.project.id}/run`);
    $("status").textContent = `done: ${state.run.rocks} rocks, seed ${state.run.seed}, ${fmt(state.run.runtime_s, 1)} s`;
    $("place").disabled = false;
    drawSection(); drawRun();
    if (state.placed) requestPlace(state.placed.x);
  } else if (job.kind === "study" || job.kind === "calibrate") {
    showTables(job);
  } else if (job.kind === "check") {
    showCheck(job.result);
    showDownloads(job, $("results"));
  } else {
    showOptimise(job);
  }
  // Said last: a test (or a user's script) that waits for "done" finds everything drawn.
  $("status").dataset.state = "done";
}

function cell(v) { const td = document.createElement("td"); td.textContent = v; return td; }

function showCheck(s) {
  const div = $("results");
  const p = s.protect, v = s.verdict;
  const untested = new Set(v ? v.untested_measures : []);
  div.innerHTML = "";
  // The verdict heads the result, as it heads check's report.
  const head = document.createElement("p");
  head.id = "check-verdict";
  head.className = v ? verdictClass(v.state) : s.ok ? "ok" : "fail";
  head.textContent = `check (${s.rocks} rocks, seed ${s.seed}): ` +
    (v ? v.headline : s.ok ? "every check holds" : "fails") +
    (p ? `; ${p.reaching} rocks reach x ≥ ${p.x} m (upper bound ${pct(p.upper_fraction)})` : "");
  if (v) head.dataset.verdict = v.state;
  div.appendChild(head);
  for (const f of (v ? v.details : s.failures)) {
    const q = document.createElement("p"); q.className = v ? "detail" : "fail"; q.textContent = f; div.appendChild(q);
  }
  const table = document.createElement("table");
  table.id = "check-table";
  for (const m of s.measures) {
    for (const c of m.checks) {
      const tr = document.createElement("tr");
      const [word, cls] = checkWord(c, untested.has(m.label));
      const w = cell(word); w.className = cls;
      tr.append(cell(m.label), cell(c.name), cell(fmt(c.value)), cell(fmt(c.bound)), cell(fmt(c.target)), w);
      table.appendChild(tr);
    }
  }
  div.appendChild(table);
}

// The job's files: design.yaml, report.html (as --report writes it) and the figures.
// The report and figures are drawn on the first click (a few seconds).
function showDownloads(job, div) {
  if (!job.files.length) return;
  const p = document.createElement("p");
  p.className = "downloads"; p.textContent = "download: ";
  for (const name of job.files) {
    const a = document.createElement("a");
    // A link cannot send a header: the token goes in its address (same origin only).
    a.href = `/api/jobs/${job.id}/files/${name}?token=${encodeURIComponent(TOKEN)}`;
    a.textContent = name; a.download = name;
    p.append(a, " ");
  }
  div.appendChild(p);
}

function showOptimise(job) {
  const s = job.result, div = $("results");
  // best is the chosen design itself (with its name); a summary from before was its name
  const chosen = s.best === null || typeof s.best === "string" ? s.best : s.best.name;
  const best = chosen === null ? null : s.alternatives.find((a) => a.name === chosen);
  div.innerHTML = "";
  const head = document.createElement("p");
  head.id = "chosen";
  head.textContent = best ? `chosen: ${best.name}, cost ${Math.round(best.cost).toLocaleString()} ${s.currency || ""}` :
    `no admissible design: ${s.reason || ""}`;
  div.appendChild(head);
  const table = document.createElement("table");
  table.id = "alternatives";
  const hr = document.createElement("tr");
  for (const h of ["family", "cost", "residual", "holds", "why not"]) { const th = document.createElement("th"); th.textContent = h; hr.appendChild(th); }
  table.appendChild(hr);
  for (const a of s.alternatives) {
    const tr = document.createElement("tr");
    if (best && a.name === best.name) tr.className = "ok";
    tr.append(cell(a.name), cell(a.cost === null ? "–" : Math.round(a.cost).toLocaleString()),
      cell(a.residual === undefined || a.residual === null ? "–" : a.residual),
      cell(a.feasible ? (a.holds_on_fresh_rocks ? "yes" : "not on fresh rocks") : "no"), cell(a.reason || ""));
    table.appendChild(tr);
  }
  div.appendChild(table);
  showDownloads(job, div);
  state.chosen = best ? best.measures : null;
  drawSection(); drawRun();
}

async function cancel() { if (state.job) await api(`/api/jobs/${state.job.id}/cancel`, {}); }

// ---- the project file ------------------------------------------------------------------
async function loadYaml() {
  const f = await api(`/api/projects/${state.project.id}/file`);
  $("yaml").value = f.text;
  // Save sends it back: the server writes only over the file this page read.
  state.fileVersion = f.version;
  $("save-file").textContent = `writes ${f.path}`;
}
async function validateYaml() {
  try { await api(`/api/projects/${state.project.id}/validate`, { text: $("yaml").value }); $("yaml-status").textContent = "valid"; }
  catch (e) { $("yaml-status").textContent = e.message; }
}
async function saveYaml() {
  const body = { text: $("yaml").value, version: state.fileVersion };
  try {
    const r = await api(`/api/projects/${state.project.id}/save`, body);
    state.fileVersion = r.version;
    $("yaml-status").textContent = `saved ${r.path}`;
  } catch (e) { $("yaml-status").textContent = e.message; }
}

async function uploadFile() {
  const f = $("upload").files[0];
  if (!f) return;
  try {
    const r = await api(`/api/projects/${state.project.id}/upload`, { path: f.name, text: await f.text() });
    $("yaml-status").textContent = `imported ${r.path}`;
  } catch (e) { $("yaml-status").textContent = e.message; }
}

// ---- materials from the library -----------------------------------------------------------
function fillSegments() {
  const p = state.project, sel = $("segment");
  sel.innerHTML = "";
  p.materials.forEach((m, i) => {
    const o = document.createElement("option"); o.value = i;
    o.textContent = `${i + 1}: x ${fmt(p.ground[i][0], 0)} to ${fmt(p.ground[i + 1][0], 0)} m, ${m}`;
    sel.appendChild(o);
  });
}
function showMaterialValues() {
  const m = (state.library || []).find((e) => e.name === $("library-material").value);
  $("material-values").textContent = m ? `law ${m.law}: ` +
    Object.entries(m.values).filter(([k]) => k !== "impact_model")
      .map(([k, v]) => `${k} ${typeof v === "object" ? JSON.stringify(v) : v}`).join(", ") +
    (m.source ? ` (source: ${m.source})` : "") : "";
}
async function loadLibrary() {
  const path = $("library-path").value;
  const sel = $("library-material");
  sel.innerHTML = ""; state.library = null; $("apply-material").disabled = true;
  try {
    const lib = await api(`/api/projects/${state.project.id}/materials` +
      (path ? `?path=${encodeURIComponent(path)}` : ""));
    state.library = lib.materials; state.libraryPath = lib.path;
    for (const m of lib.materials) {
      const o = document.createElement("option"); o.value = m.name; o.textContent = `${m.name} (${m.law})`;
      sel.appendChild(o);
    }
    $("apply-material").disabled = false;
    $("material-status").textContent = `${lib.materials.length} materials in ${lib.path}`;
  } catch (e) { $("material-status").textContent = e.message; }
  showMaterialValues();
}
async function applyMaterial() {
  const body = { segment: Number($("segment").value), material: $("library-material").value,
    library: state.libraryPath };
  try {
    const r = await api(`/api/projects/${state.project.id}/materials`, body);
    const { yaml, ...project } = r;
    state.project = project; state.run = null; $("place").disabled = true;
    $("yaml").value = yaml;
    $("yaml-status").textContent = "changed in the page, not saved: Save writes this file";
    $("material-status").textContent = project.edits[project.edits.length - 1] + "; simulate again";
    fillSegments(); drawSection(); drawRun();
  } catch (e) { $("material-status").textContent = e.message; }
}

// ---- start ---------------------------------------------------------------------------
async function selectProject(id) {
  state.project = await api(`/api/projects/${id}`);
  state.run = state.project.run; state.placed = null; state.chosen = null;
  $("results").innerHTML = "";
  $("title").textContent = state.project.name;
  $("description").textContent = state.project.description;
  $("rocks").value = state.project.rocks; $("seed").value = state.project.seed;
  $("place").disabled = !state.run;
  enableJobs();
  $("with-own-label").hidden = !state.project.measures.length;
  drawSection(); drawRun(); fillSegments();
  $("library-path").value = ""; $("library-material").innerHTML = ""; state.library = null;
  $("apply-material").disabled = true; $("material-status").textContent = "";
  if (state.project.library) loadLibrary();
  loadYaml().catch((e) => showError(e.message));
}

async function start() {
  try {
    const [list, plugins] = await Promise.all([api("/api/projects"), api("/api/plugins")]);
    state.projects = list.projects; state.plugins = plugins;
    for (const p of list.projects) {
      const o = document.createElement("option"); o.value = p.id; o.textContent = `${p.name} (${p.file})`;
      $("project").appendChild(o);
    }
    for (const m of plugins.measures) {
      const o = document.createElement("option"); o.value = m.kind; o.textContent = `${m.kind}: ${m.summary}`;
      $("measure-type").appendChild(o);
    }
    $("measure-type").value = plugins.measures.some((m) => m.kind === "fence") ? "fence" : plugins.measures[0].kind;
    buildForm();
    $("measure-type").onchange = () => { buildForm(); if (state.placed) placeMeasure(); };
    $("project").onchange = () => selectProject($("project").value);
    $("simulate").onclick = simulate; $("cancel").onclick = cancel; $("place").onclick = placeMeasure;
    $("with-own").onchange = () => { if (state.placed && state.run) requestPlace(state.placed.x); };
    $("check").onclick = checkDesign; $("optimise").onclick = optimiseDesign;
    $("study").onclick = studyProject; $("calibrate").onclick = calibrateProject;
    $("upload").onchange = uploadFile;
    $("validate").onclick = validateYaml; $("save").onclick = saveYaml;
    $("library-load").onclick = loadLibrary; $("apply-material").onclick = applyMaterial;
    $("library-material").onchange = showMaterialValues;
    if (list.projects.length) await selectProject(list.projects[0].id);
    document.body.dataset.ready = "1";
  } catch (e) { showError(e.message); }
}
start();
