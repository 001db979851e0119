// The bicycle's page (a model with a steer input, `twv serve --model whipple`): every change of
// the steer gains, the speed or the push sends them to the JSON API (ride, linearize in
// parallel) and redraws from the answers; the eigenvalues against speed (steady) are fetched
// once per parameter change. Nothing is computed here but drawing. Shared helpers: common.js.
"use strict";

const GAINS = ["k_phi", "k_delta", "k_phi_dot", "k_delta_dot"];
const steerGains = () => Object.fromEntries(GAINS.map((k) => [k, num(k)]));
const speed = () => num("speed");
// The rate filter's τ [s] from the field in ms; null (none) when empty.
const rateFilter = () => ($("filter").value.trim() === "" ? null : num("filter") / 1000);
// The eigenvalues against speed are drawn over this range [m/s] (LO:HI:STEP, the steady job's).
const SPEEDS = "0:10:0.02";

function setupBikeCharts() {
  Chart.defaults.font.size = 12;
  chart("c-lean", "lean φ after the push", "t [s]", "φ [rad]");
  chart("c-steer", "steer angle δ", "t [s]", "δ [rad]");
  chart("c-poles", "steer-loop poles at this speed", "Re s [1/s]", "Im s [1/s]", { scatter: true });
  chart("c-eig", "unsteered: real parts of the eigenvalues", "speed v [m/s]", "Re λ [1/s]");
}

function showRide(answer) {
  const s = answer.series;
  const r = answer.result;
  draw("c-lean", [{ label: "φ", data: xy(s.t, s.phi) }]);
  draw("c-steer", [{ label: "δ", data: xy(s.t, s.delta) }]);
  setVerdict("ride-verdict", r.verdict);
  $("peak").textContent = fmt(r.peak, 4, " rad");
  $("tail").textContent = fmt(r.tail_peak, 3, " rad");
}

function showLoop(answer) {
  const r = answer.result;
  const st = r.steer;
  setVerdict("loop-verdict", st.loop_poles.stable ? "stable" : "unstable");
  showMarginNumbers(st.margins);
  const closed = st.loop_poles.eigenvalues.map(([re, im]) => ({ x: re, y: im }));
  const open = r.open_loop
    .filter((m) => m.kind !== "Drift")
    .map((m) => ({ x: m.eigenvalue[0], y: m.eigenvalue[1] }));
  draw("c-poles", [
    { label: "steered", data: closed, line: false },
    { label: "unsteered", data: open, line: false, pointStyle: "crossRot" },
  ]);
  twv.closedLoopRe = closed.map((p) => p.x);
  drawEigenvalues();
}

// The unsteered eigenvalues' real parts against speed (one curve per eigenvalue, sorted), the
// current speed and the steered poles' real parts there.
function drawEigenvalues() {
  const steady = twv.last.steady;
  if (!steady) return;
  const pts = steady.result.points;
  const curves = pts[0].eigenvalues.map((_, k) => ({
    label: `λ${k + 1}`,
    data: pts.map((p) => ({ x: p.speed, y: p.eigenvalues[k][0] })),
  }));
  const res = pts.flatMap((p) => p.eigenvalues.map((e) => e[0]));
  const lo = Math.max(Math.min(...res), -20), hi = Math.min(Math.max(...res), 20);
  curves.push({ label: "this speed", data: vline(speed(), lo, hi), color: "#999", dash: [4, 3] });
  if (twv.closedLoopRe) {
    curves.push({
      label: "steered",
      data: twv.closedLoopRe.map((re) => ({ x: speed(), y: re })),
      line: false,
      color: "#000",
    });
  }
  draw("c-eig", curves);
  const c = charts["c-eig"];
  Object.assign(c.options.scales.y, { min: lo, max: hi });
  c.update("none");
}

function showSteady(answer) {
  const r = answer.result;
  $("band").textContent =
    r.weave_speed === null || r.capsize_speed === null
      ? "no self-stable band in 0–10 m/s"
      : `self-stable from ${fmt(r.weave_speed, 4)} m/s (weave) to ${fmt(r.capsize_speed, 4)} m/s (capsize)`;
  drawEigenvalues();
}

async function refreshSteady() {
  try {
    twv.last.steady = await api("/api/steady", { params, options: { speed: SPEEDS } });
    showSteady(twv.last.steady);
  } catch (e) {
    showError(`steady: ${e.message}`);
  }
}

async function update() {
  const generation = ++twv.generation;
  const g = steerGains(); // what this update draws (the sliders may move while it runs)
  const v = speed();
  const tau = rateFilter();
  const body = (options) => ({ params, options });
  const law = { speed: v, steer_gains: g, steer_filter: tau };
  const jobs = {
    ride: api("/api/ride", body({ ...law, perturb: { w_phi: num("push") }, t_end: num("t-end") })),
    loop: api("/api/linearize", body(law)),
  };
  if (!(await settle(generation, jobs, { ride: showRide, loop: showLoop }))) return; // a newer update is on its way
  twv.gains = g;
  twv.speed = v;
  twv.filter = tau;
  twv.updates += 1;
}

let queued = false;
function schedule() {
  for (const id of [...GAINS, "speed"]) $(`${id}-out`).textContent = $(id).value;
  if (queued) return;
  queued = true;
  requestAnimationFrame(() => {
    queued = false;
    update();
  });
}

async function tune() {
  const status = $("tune-status");
  status.textContent = "tuning…";
  try {
    const options = { speed: String(speed()), spec: $("spec").value, rate_filter: rateFilter() };
    const answer = await api("/api/steer", { params, options });
    const p = answer.result.points[0];
    const c = p.certificate;
    setVerdict("tune-status", p.met ? "met" : "not_met");
    if (!c) {
      status.textContent = `${p.tune_status.kind || "failed"}: no gains (best fraction ${fmt(p.best_fraction, 3)})`;
      return;
    }
    for (const k of GAINS) $(k).value = c.analysis.gains[k];
    status.textContent =
      `${p.met ? "met" : "not met"}: ${GAINS.map((k) => `${k} ${c.analysis.gains[k].toFixed(2)}`).join(", ")}` +
      ` (the sliders round to their steps)`;
    schedule();
  } catch (e) {
    status.textContent = e.message;
  }
}

async function start() {
  const answer = await api("/api/model");
  const model = (twv.model = answer.result);
  $("model-name").textContent = model.model;
  $("params-origin").textContent = `parameters: ${model.params_origin}`;
  if (!model.inputs.includes("T_delta")) {
    showError(`${model.model} has no steer input (T_delta): the bicycle page needs one; the vehicle's page is /`);
    return;
  }
  // The start: lean-rate feedback that balances the benchmark bicycle at 3 m/s.
  const start = { k_phi: 0, k_delta: 0, k_phi_dot: 15, k_delta_dot: 0 };
  for (const k of GAINS) $(k).value = start[k];
  $("defaults").textContent =
    `It starts at 3 m/s with lean-rate feedback alone (k_phi_dot = 15 N m s/rad) and a push of ` +
    `0.5 rad/s, with the parameters of ${model.params_origin}.`;
  paramFields(model, () => {
    refreshSteady();
    schedule();
  });
  setupBikeCharts();
  for (const id of [...GAINS, "speed"]) $(id).addEventListener("input", schedule);
  for (const id of ["push", "t-end", "filter"]) $(id).addEventListener("change", schedule);
  $("tune").addEventListener("click", tune);
  refreshSteady();
  schedule();
}

start().catch((e) => showError(`cannot start: ${e.message}`));
