// What both pages share (the vehicle's, app.js, and the bicycle's, bicycle.js): the JSON API,
// the number fields, the charts, the verdicts, the margins and the parameter fields. Nothing is
// computed here but drawing. `window.twv` exposes the last answers and an update counter (the
// browser test reads them).
"use strict";

const $ = (id) => document.getElementById(id);
const twv = (window.twv = { updates: 0, generation: 0, last: {}, timing: {}, model: null });
const params = {}; // vehicle parameter overrides by IR name
let stateIndex = {};

async function api(path, body) {
  const init = body === undefined ? {} : {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify(body),
  };
  const response = await fetch(path, init);
  const answer = await response.json();
  if (!response.ok) throw new Error(answer.error || response.statusText);
  return answer;
}

const num = (id) => Number($(id).value);
const optional = (id) => ($(id).value.trim() === "" ? null : Number($(id).value));
const fmt = (v, digits = 3, unit = "") => (v === null || v === undefined ? "—" : `${Number(v).toPrecision(digits)}${unit}`);

const degrees = (rad) => `(${((rad * 180) / Math.PI).toFixed(2)}°)`;

// --- charts -----------------------------------------------------------------------------------

const COLORS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"];
const charts = (twv.charts = {});

function chart(id, title, xLabel, yLabel, { logX = false, scatter = false } = {}) {
  charts[id] = new Chart($(id), {
    type: scatter ? "scatter" : "line",
    data: { datasets: [] },
    options: {
      animation: false,
      responsive: true,
      maintainAspectRatio: false,
      parsing: false,
      normalized: true,
      plugins: { title: { display: true, text: title }, legend: { labels: { boxWidth: 12 } } },
      elements: { point: { radius: scatter ? 3 : 0 }, line: { borderWidth: 1.5 } },
      scales: {
        x: {
          type: logX ? "logarithmic" : "linear",
          title: { display: true, text: xLabel },
          // Log axes: label the decades only.
          ticks: logX ? { callback: (v) => (Math.abs(Math.log10(v) - Math.round(Math.log10(v))) < 1e-9 ? v : "") } : {},
        },
        y: { title: { display: true, text: yLabel } },
      },
    },
  });
}

function draw(id, datasets) {
  const c = charts[id];
  c.data.datasets = datasets.map((d, i) => ({
    borderColor: d.color || COLORS[i % COLORS.length],
    backgroundColor: d.color || COLORS[i % COLORS.length],
    showLine: d.line !== false,
    pointRadius: d.line === false ? 4 : 0,
    borderDash: d.dash || [],
    ...d,
  }));
  c.update("none");
}

const xy = (xs, ys) => xs.map((x, i) => ({ x, y: ys[i] }));
const vline = (x, lo, hi) => [{ x, y: lo }, { x, y: hi }];

function setVerdict(id, verdict) {
  const el = $(id);
  el.textContent = verdict.replace("_", " ");
  el.className = `verdict ${verdict}`;
  el.dataset.verdict = verdict;
}

function showError(message) {
  const box = $("error");
  box.hidden = !message;
  box.textContent = message || "";
  document.querySelectorAll(".field-error").forEach((el) => (el.textContent = ""));
  if (!message) return;
  // A parameter the server refused: say so beside its field too.
  const named = /`([^`]+)`/.exec(message);
  if (named && $(`err-${named[1]}`)) $(`err-${named[1]}`).textContent = message;
}

// The margins of a stable loop into the fields gm, pm, dm and disk (each with its number in
// data-value for the browser test), or "undefined" for an unstable one.
function showMarginNumbers(m) {
  const set = (id, text, value) => {
    $(id).textContent = text;
    $(id).dataset.value = value === null || value === undefined ? "" : String(value);
  };
  if (m) {
    set("gm", `[${fmt(m.gain_margin_lower, 4)}, ${m.gain_margin_upper === null ? "∞" : fmt(m.gain_margin_upper, 4)}]`, m.gain_margin_lower);
    set("pm", m.phase_margin ? `${m.phase_margin.deg.toFixed(2)}° at ${fmt(m.phase_margin.frequency, 4)} rad/s` : "∞ (no crossover)", m.phase_margin ? m.phase_margin.deg : null);
    set("dm", m.delay_margin === null ? "∞" : fmt(m.delay_margin, 3, " s"), m.delay_margin);
    set("disk", `α = ${fmt(m.disk_alpha, 4)} (±${m.disk_phase_deg.toFixed(1)}°)`, m.disk_alpha);
  } else {
    for (const id of ["gm", "pm", "dm", "disk"]) set(id, "undefined (loop not stable)", null);
  }
}

// One field per parameter with its description; a change goes into `params` (overrides by IR
// name, sent with every request) and calls `changed`.
function paramFields(model, changed) {
  const box = $("params");
  for (const p of model.params) {
    const div = document.createElement("div");
    div.className = "param";
    // The description in view, not only as a tooltip (a touch screen shows no tooltips).
    div.innerHTML = `<label>${p.name} [${p.unit}] <input type="number" step="any" id="param-${p.name}"></label><div class="desc"></div><div class="field-error" id="err-${p.name}"></div>`;
    div.querySelector(".desc").textContent = p.description;
    box.append(div);
    const input = div.querySelector("input");
    input.value = p.value;
    input.addEventListener("change", () => {
      const v = Number(input.value);
      if (input.value.trim() === "" || !Number.isFinite(v)) {
        $(`err-${p.name}`).textContent = `${p.name}: not a number`;
        return;
      }
      params[p.name] = v;
      changed();
    });
  }
}

// One update's requests (`jobs`: name → pending answer), run in parallel: each answer is kept
// in twv.last and drawn by its handler, the first error shown, the server times printed in the
// header. Returns false, drawing nothing, when a newer update (`twv.generation`) has started.
async function settle(generation, jobs, handlers) {
  const names = Object.keys(jobs);
  const settled = await Promise.allSettled(Object.values(jobs));
  if (generation !== twv.generation) return false;
  const errors = [];
  settled.forEach((s, i) => {
    const name = names[i];
    if (s.status === "rejected") {
      errors.push(`${name}: ${s.reason.message}`);
      return;
    }
    twv.last[name] = s.value;
    twv.timing[name] = s.value.server_ms;
    handlers[name](s.value);
  });
  showError(errors.length ? errors[0] : "");
  const times = names.filter((n) => n in twv.timing).map((n) => `${n} ${twv.timing[n].toFixed(1)}`);
  const slowest = Math.max(...names.map((n) => twv.timing[n] || 0));
  $("timing").textContent = `server ms: ${times.join(" · ")} (slowest ${slowest.toFixed(1)} ms)`;
  $("timing").dataset.slowest = String(slowest);
  twv.errors = errors;
  return true;
}
