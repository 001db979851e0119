// The live page: every control change sends the current settings to the JSON API (simulate,
// margins, lyapunov, phase in parallel) and redraws from the answers. Nothing is computed here
// but drawing: every number and verdict shown comes from the server. `window.twv` exposes the
// last answers and an update counter (the browser test reads them). Shared helpers: common.js.
"use strict";

function gains() {
  return { kp: num("kp"), ki: num("ki"), kd: num("kd") };
}

function controller() {
  const setpoint = $("setpoint").value === "sine" ? { kind: "sine", amplitude: 0.03 } : { kind: "zero" };
  return {
    pitch: {
      gains: gains(),
      setpoint,
      derivative_filter: optional("filter"),
      saturation: optional("saturation"),
    },
  };
}

// The initial tilt in rad (the unit of every angle twv takes and prints): the number field is
// exact (the study's 0.1 rad), the slider moves in 0.001 rad steps; degrees are shown beside.
const tilt = () => num("tilt-num");
const loopOptions = () => ({ lag: num("lag"), delay: num("delay") });


function setupCharts() {
  // Text at least 12 px: legible on a phone.
  Chart.defaults.font.size = 12;
  chart("c-phi", "pitch Φ", "t [s]", "Φ [rad]");
  // "dΦ/dt", not a combining dot: Φ̇ lost its dot with the fonts a headless Debian has.
  chart("c-phidot", "pitch rate dΦ/dt", "t [s]", "dΦ/dt = w_y [rad/s]");
  chart("c-force", "base force F", "t [s]", "F [N]");
  chart("c-vx", "forward speed v_x", "t [s]", "v_x [m/s]");
  chart("c-phase", "phase portrait (±tilt, ±2·tilt)", "Φ [rad]", "dΦ/dt [rad/s]");
  chart("c-poles", "closed-loop poles", "Re s [1/s]", "Im s [1/s]", { scatter: true });
  chart("c-mag", "Bode magnitude of L(jω)", "ω [rad/s]", "|L| [dB]", { logX: true });
  chart("c-arg", "Bode phase of L(jω)", "ω [rad/s]", "∠L [°]", { logX: true });
  chart("c-nyquist", "Nyquist (|L| ≤ 5, equal axes)", "Re L [1]", "Im L [1]");
}

// --- one update ----------------------------------------------------------------------------

function showSimulation(answer) {
  const s = answer.series;
  const r = answer.result;
  draw("c-phi", [{ label: "Φ", data: xy(s.t, s.phi) }, { label: "Φ_ref", data: xy(s.t, s.phi_ref), dash: [4, 3] }]);
  draw("c-phidot", [{ label: "dΦ/dt", data: xy(s.t, s.w_y) }]);
  draw("c-force", [{ label: "F", data: xy(s.t, s.F) }, { label: "F command", data: xy(s.t, s.F_cmd), dash: [4, 3] }]);
  draw("c-vx", [{ label: "v_x", data: xy(s.t, s.v_x) }]);
  const m = r.metrics;
  setVerdict("recovery", r.recovery);
  $("settling").textContent = fmt(m.phi.settling_time, 3, " s");
  $("overshoot").textContent = m.phi.overshoot === null ? "—" : `${(100 * m.phi.overshoot).toFixed(1)} %`;
  $("peak-force").textContent = fmt(m.peak_force, 4, " N");
}

function showMargins(answer) {
  const r = answer.result;
  const p = r.pitch;
  setVerdict("loop-verdict", p.verdict);
  showMarginNumbers(p.margins);
  const poles = p.loop_poles.map(([re, im]) => ({ x: re, y: im }));
  const open = r.open_loop.map((mode) => ({ x: mode.eigenvalue[0], y: mode.eigenvalue[1] }));
  draw("c-poles", [
    { label: "closed loop", data: poles, line: false },
    { label: "open loop", data: open, line: false, pointStyle: "crossRot" },
  ]);
  const f = p.response;
  if (!f) {
    for (const id of ["c-mag", "c-arg", "c-nyquist"]) draw(id, []);
    return;
  }
  const magLo = Math.min(...f.magnitude_db), magHi = Math.max(...f.magnitude_db);
  const argLo = Math.min(...f.phase_deg), argHi = Math.max(...f.phase_deg);
  const mag = [{ label: "|L|", data: xy(f.w, f.magnitude_db) }];
  const arg = [{ label: "∠L", data: xy(f.w, f.phase_deg) }];
  f.gain_crossovers.forEach((w) => {
    mag.push({ label: `|L| = 1 at ${fmt(w, 4)}`, data: vline(w, magLo, magHi), dash: [4, 3] });
    arg.push({ label: `|L| = 1 at ${fmt(w, 4)}`, data: vline(w, argLo, argHi), dash: [4, 3] });
  });
  f.phase_crossovers.filter((w) => w > 0).forEach((w) => {
    mag.push({ label: `∠L = 180° at ${fmt(w, 4)}`, data: vline(w, magLo, magHi), dash: [2, 2] });
  });
  draw("c-mag", mag);
  draw("c-arg", arg);
  const near = f.re.map((re, i) => ({ x: re, y: f.im[i] })).filter((p) => Math.hypot(p.x, p.y) <= 5);
  const circle = (c, r) => Array.from({ length: 121 }, (_, k) => ({ x: c + r * Math.cos((k * Math.PI) / 60), y: r * Math.sin((k * Math.PI) / 60) }));
  const nyquist = [
    { label: "ω > 0", data: near },
    { label: "ω < 0", data: near.map((p) => ({ x: p.x, y: -p.y })), dash: [4, 3] },
    { label: "|L| = 1", data: circle(0, 1), color: "#999" },
    { label: "−1", data: [{ x: -1, y: 0 }], line: false, color: "#d62728", pointStyle: "cross", pointRadius: 8 },
  ];
  // The disk margin's exclusion disk (from the server): L stays outside, touching it.
  if (f.disk) nyquist.push({ label: "disk margin", data: circle(f.disk.center, f.disk.radius), color: "#9467bd", dash: [2, 2] });
  draw("c-nyquist", nyquist);
  equalAxes("c-nyquist", nyquist.flatMap((d) => d.data));
}

// One unit of x as long on the screen as one unit of y (a circle drawn round), around `points`.
function equalAxes(id, points) {
  const c = charts[id];
  const xs = points.map((p) => p.x), ys = points.map((p) => p.y);
  const [x0, x1, y0, y1] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
  // Twice: the tick labels the first pass chooses change the plot area the second one fits.
  for (let pass = 0; pass < 2; pass++) {
    const a = c.chartArea;
    const w = a.right - a.left, h = a.bottom - a.top;
    const perPixel = 1.05 * Math.max((x1 - x0) / w, (y1 - y0) / h);
    const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
    // Round ticks, the same step on both axes, and no odd numbers at the ends.
    const raw = (perPixel * Math.max(w, h)) / 6;
    const decade = 10 ** Math.floor(Math.log10(raw));
    const stepSize = [1, 2, 5, 10].map((m) => m * decade).find((s) => s >= raw);
    const ticks = { stepSize, includeBounds: false };
    Object.assign(c.options.scales.x, { min: cx - (perPixel * w) / 2, max: cx + (perPixel * w) / 2, ticks });
    Object.assign(c.options.scales.y, { min: cy - (perPixel * h) / 2, max: cy + (perPixel * h) / 2, ticks });
    c.update("none");
  }
}

function showLyapunov(answer) {
  const r = answer.result;
  setVerdict("lyap-verdict", r.verdict);
  const v = r.point.value;
  $("lyap").textContent = v === null ? `no value (${r.point.status})` : `λ1 = ${v.toFixed(4)} 1/s (resolution ±${fmt(r.resolution, 3)})`;
  $("lyap").dataset.value = v === null ? "" : String(v);
}

function showPhase(answer) {
  draw("c-phase", answer.series[0].map((run) => ({
    label: `Φ0 = ${run.phi0.toFixed(3)}`,
    data: xy(run.phi, run.phi_dot),
  })));
}

async function update() {
  const generation = ++twv.generation;
  const g = gains(); // what this update draws (the sliders may move while it runs)
  const c = controller();
  const body = (settings) => ({ params, settings });
  const jobs = {
    simulate: api("/api/simulate", body({ controller: c, phi0: tilt() })),
    margins: api("/api/linearize", body({ gains: g, loop_options: loopOptions(), frequency_points: 300 })),
    lyapunov: api("/api/exponent", body({ controller: c, tilt: tilt() })),
    phase: api(
      "/api/phase",
      body({ portraits: [["current gains", { closed: c }]], tilts: [tilt(), -tilt(), 2 * tilt(), -2 * tilt()] }),
    ),
  };
  const shown = { simulate: showSimulation, margins: showMargins, lyapunov: showLyapunov, phase: showPhase };
  if (!(await settle(generation, jobs, shown))) return; // a newer update is on its way
  twv.gains = g;
  twv.updates += 1;
  markMap();
}

let queued = false;
function schedule() {
  for (const id of ["kp", "ki", "kd"]) $(`${id}-out`).textContent = $(id).value;
  $("tilt-deg").textContent = degrees(tilt());
  if (queued) return;
  queued = true;
  requestAnimationFrame(() => {
    queued = false;
    update();
  });
}

// --- the map ---------------------------------------------------------------------------------

const MAP_N = 20;
// Room for the axes' ticks and labels, and the colour bar on the right [CSS px].
const MAP_PAD = { l: 62, b: 44, t: 8, r: 92 };
let map = null; // { kp: [..], kd: [..], points: [[point per kp] per kd row] }

function mapAxes() {
  const kpMax = Number($("kp").max), kdMax = Number($("kd").max);
  const axis = (hi) => Array.from({ length: MAP_N }, (_, i) => (hi * (i + 0.5)) / MAP_N);
  return { kp: axis(kpMax), kd: axis(kdMax), kpMax, kdMax };
}

async function computeMap() {
  const axes = mapAxes();
  map = { ...axes, rows: [] };
  $("map").disabled = true;
  $("map-status").textContent = "";
  const started = performance.now();
  try {
    for (let j = 0; j < MAP_N; j++) {
      const c = controller();
      const settings = {
        grid: {
          kp: { lo: axes.kp[0], hi: axes.kp[MAP_N - 1], n: MAP_N },
          kd: { lo: axes.kd[j], hi: axes.kd[j], n: 1 },
          ki: c.pitch.gains.ki ? { lo: c.pitch.gains.ki, hi: c.pitch.gains.ki, n: 1 } : null,
        },
        metric: "max-lyapunov",
        tilt: tilt(),
        controller: c,
        metric_settings: twv.model.defaults.exponent.metric_settings,
      };
      const answer = await api("/api/sweep", { params, settings });
      map.rows.push(answer.result);
      $("map-progress").value = (j + 1) / MAP_N;
      drawMap();
    }
    $("map-status").textContent = `${MAP_N * MAP_N} points in ${((performance.now() - started) / 1000).toFixed(1)} s`;
  } catch (e) {
    $("map-status").textContent = e.message;
  }
  $("map").disabled = false;
}

// The canvas at the size the page gives it, sharp on high-density screens; sizes in CSS px.
function mapCanvas() {
  const canvas = $("c-map");
  const ratio = window.devicePixelRatio || 1;
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== Math.round(w * ratio) || canvas.height !== Math.round(h * ratio)) {
    canvas.width = Math.round(w * ratio);
    canvas.height = Math.round(h * ratio);
  }
  const g = canvas.getContext("2d");
  g.setTransform(ratio, 0, 0, ratio, 0, 0);
  return { canvas, g, w, h, plotW: w - MAP_PAD.l - MAP_PAD.r, plotH: h - MAP_PAD.b - MAP_PAD.t };
}

const niceTicks = (hi, n = 4) => Array.from({ length: n + 1 }, (_, i) => (hi * i) / n);

function mapColor(value, scale) {
  if (value === null) return "#bbb";
  const a = Math.min(1, Math.abs(value) / scale) * 0.85 + 0.15;
  return value < 0 ? `rgba(31,119,180,${a})` : `rgba(214,39,40,${a})`;
}

function drawMap() {
  const { g, w, h, plotW, plotH } = mapCanvas();
  g.clearRect(0, 0, w, h);
  if (!map) return;
  const cw = plotW / MAP_N, ch = plotH / MAP_N;
  const values = map.rows.flat().filter((p) => p.value !== null).map((p) => Math.abs(p.value));
  const scale = Math.max(1e-9, ...values);
  twv.mapScale = scale;
  map.rows.forEach((row, j) => row.forEach((p, i) => {
    g.fillStyle = mapColor(p.value, scale);
    g.fillRect(MAP_PAD.l + i * cw, MAP_PAD.t + plotH - (j + 1) * ch, cw - 1, ch - 1);
  }));
  g.fillStyle = "#222";
  g.strokeStyle = "#222";
  g.font = "12px sans-serif";
  // Ticks with values on both axes (the cells are centred on the axis values).
  g.textAlign = "center";
  for (const v of niceTicks(map.kpMax)) {
    const x = MAP_PAD.l + (v / map.kpMax) * plotW;
    g.fillRect(x, MAP_PAD.t + plotH, 1, 5);
    g.fillText(String(Math.round(v)), x, MAP_PAD.t + plotH + 17);
  }
  g.fillText("Kp [N/rad]", MAP_PAD.l + plotW / 2, h - 6);
  g.textAlign = "right";
  for (const v of niceTicks(map.kdMax)) {
    const y = MAP_PAD.t + plotH - (v / map.kdMax) * plotH;
    g.fillRect(MAP_PAD.l - 5, y, 5, 1);
    g.fillText(String(Math.round(v)), MAP_PAD.l - 7, y + 4);
  }
  g.save();
  g.translate(13, MAP_PAD.t + plotH / 2);
  g.rotate(-Math.PI / 2);
  g.textAlign = "center";
  g.fillText("Kd [N s/rad]", 0, 0);
  g.restore();
  // The colour bar: λ1 from −scale (blue) through 0 to +scale (red), with its ticks.
  const barX = MAP_PAD.l + plotW + 16, barW = 14, steps = 60;
  for (let k = 0; k < steps; k++) {
    const v = scale - (2 * scale * (k + 0.5)) / steps;
    g.fillStyle = mapColor(v, scale);
    g.fillRect(barX, MAP_PAD.t + (k * plotH) / steps, barW, plotH / steps + 1);
  }
  g.fillStyle = "#222";
  g.textAlign = "left";
  for (const f of [1, 0.5, 0, -0.5, -1]) {
    const y = MAP_PAD.t + ((1 - f) / 2) * plotH;
    g.fillRect(barX + barW, y, 4, 1);
    g.fillText((f * scale).toPrecision(2), barX + barW + 6, y + 4);
  }
  g.save();
  g.translate(w - 6, MAP_PAD.t + plotH / 2);
  g.rotate(-Math.PI / 2);
  g.textAlign = "center";
  g.fillText("λ1 [1/s]", 0, 0);
  g.restore();
  twv.mapColorBar = { x: barX, width: barW, min: -scale, max: scale };
  markMap();
}

function markMap() {
  if (!map) return;
  const { g, plotW, plotH } = mapCanvas();
  const x = MAP_PAD.l + (num("kp") / map.kpMax) * plotW;
  const y = MAP_PAD.t + plotH - (num("kd") / map.kdMax) * plotH;
  g.strokeStyle = "#000";
  g.lineWidth = 2;
  g.beginPath();
  g.arc(x, y, 6, 0, 2 * Math.PI);
  g.stroke();
}

function clickMap(event) {
  if (!map) return;
  const { canvas, plotW, plotH } = mapCanvas();
  const rect = canvas.getBoundingClientRect();
  const fx = (event.clientX - rect.left - MAP_PAD.l) / plotW;
  const fy = (MAP_PAD.t + plotH - (event.clientY - rect.top)) / plotH;
  if (fx < 0 || fx > 1 || fy < 0 || fy > 1) return;
  const i = Math.min(MAP_N - 1, Math.floor(fx * MAP_N)), j = Math.min(MAP_N - 1, Math.floor(fy * MAP_N));
  $("kp").value = map.kp[i];
  $("kd").value = map.kd[j];
  drawMap();
  schedule();
}

// --- tuning ----------------------------------------------------------------------------------

async function tune() {
  $("tune").disabled = true;
  $("tune-status").textContent = "tuning…";
  try {
    const answer = await api("/api/tune", { params, settings: { spec: $("spec").value, tilt: tilt(), options: { loop_options: loopOptions() } } });
    const r = answer.result;
    const cert = r.result.certificate;
    $("tune-status").innerHTML = "";
    const verdict = document.createElement("span");
    $("tune-status").append(verdict, ` (${answer.server_ms.toFixed(0)} ms)`);
    verdict.textContent = r.verdict.replace("_", " ");
    verdict.className = `verdict ${r.verdict}`;
    if (cert && r.verdict === "met") {
      // A slider clamps a value beyond its range: widen the range to the certified gains (and
      // say so) rather than show gains the certificate is not about.
      const widened = [];
      for (const k of ["kp", "ki", "kd"]) {
        const slider = $(k), value = cert.gains[k];
        if (value > Number(slider.max)) {
          slider.max = String(Math.ceil(value));
          widened.push(`${k} to ${slider.max}`);
        }
        slider.value = value;
      }
      if (widened.length) $("tune-status").append(`; slider range widened: ${widened.join(", ")}`);
      twv.tuned = cert.gains;
      schedule();
    }
  } catch (e) {
    $("tune-status").textContent = e.message;
  }
  $("tune").disabled = false;
}

// --- start -----------------------------------------------------------------------------------

async function start() {
  const answer = await api("/api/model");
  const model = (twv.model = answer.result);
  // A two-wheeler with a steer input (the bicycle) has its own page.
  if (model.inputs.includes("T_delta")) {
    location.replace("/bicycle");
    return;
  }
  $("model-name").textContent = model.model;
  $("params-origin").textContent = `parameters: ${model.params_origin}`;
  model.states.forEach((s, i) => (stateIndex[s] = i));
  const g = model.defaults.linearize.gains;
  $("kp").value = g.kp;
  $("ki").value = g.ki;
  $("kd").value = g.kd;
  const phi0 = model.defaults.simulate.phi0;
  $("tilt-num").value = String(phi0);
  $("tilt").value = String(phi0);
  $("defaults").textContent =
    `It starts at the study's PD (Kp = ${g.kp} N/rad, Kd = ${g.kd} N s/rad), its setpoint 0.03·sin Φ ` +
    `and its initial tilt of ${phi0} rad ${degrees(phi0)}, with the parameters of ${model.params_origin}.`;
  paramFields(model, schedule);
  setupCharts();
  for (const id of ["kp", "ki", "kd"]) $(id).addEventListener("input", schedule);
  // Slider and field move together; the field holds the exact value.
  $("tilt").addEventListener("input", () => {
    $("tilt-num").value = $("tilt").value;
    schedule();
  });
  $("tilt-num").addEventListener("change", () => {
    $("tilt").value = $("tilt-num").value;
    schedule();
  });
  window.addEventListener("resize", () => {
    drawMap();
    if (twv.last.margins) showMargins(twv.last.margins);
  });
  for (const id of ["setpoint", "saturation", "filter", "lag", "delay"]) $(id).addEventListener("change", schedule);
  $("map").addEventListener("click", computeMap);
  $("c-map").addEventListener("click", clickMap);
  $("tune").addEventListener("click", tune);
  schedule();
}

start().catch((e) => showError(`cannot start: ${e.message}`));
