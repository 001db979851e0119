//! The JSON API and the page's files: a request (method, path, body) to a [`Reply`], with no
//! socket involved, so that tests call it directly.
//!
//! Every `POST /api/<job>` takes `{"params": {NAME: VALUE, …}, "settings": {…}}` (both
//! optional): `params` sets vehicle parameters by their IR names (checked like a parameter
//! file's values; an impossible inertia is refused naming it), `settings` is the job's settings
//! type of the library, read by serde with its defaults. The answer is
//! `{"server_ms": …, "result": …}`, `result` being the library's result serialised as
//! `twv <job> --json` prints it (a simulation adds `"series"`, its samples by column). Errors
//! are `{"error": "…"}` with 400 (malformed), 404, 405, 413 (body or work over a limit) or 422
//! (refused by the library's validation, or the run failed).

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::time::Instant;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use twv_analysis::api::{
    self, Drive, LinearSettings, PhaseSettings, Silent, SimSettings, SweepSettings, TuneSettings,
};
use twv_analysis::control::{ControllerSettings, RunSettings};
use twv_analysis::model::ResolvedModel;
use twv_analysis::sweep::{Axis, Grid, Metric, MetricSettings, PointResult, Status};

use crate::assets;
use crate::limits::{self, LIMITS};

/// What the server knows: the model it was started with.
pub struct State {
    model: ResolvedModel,
}

impl State {
    /// The state of a server for `model`.
    pub fn new(model: ResolvedModel) -> Self {
        Self { model }
    }
}

/// An HTTP answer.
#[derive(Debug, Clone, PartialEq)]
pub struct Reply {
    pub status: u16,
    pub content_type: &'static str,
    pub body: Vec<u8>,
}

const JSON: &str = "application/json";

impl Reply {
    fn json(text: String) -> Self {
        Self {
            status: 200,
            content_type: JSON,
            body: text.into_bytes(),
        }
    }

    /// `{"error": message}` with `status`.
    pub fn error(status: u16, message: String) -> Self {
        #[derive(Serialize)]
        struct Error {
            error: String,
        }
        Self {
            status,
            content_type: JSON,
            body: serde_json::to_vec(&Error { error: message }).expect("a string serialises"),
        }
    }

    /// The answer to a body over [`limits::MAX_BODY`].
    pub fn too_large_body(bytes: usize) -> Self {
        Self::error(
            413,
            format!(
                "request body: {bytes} bytes is over this server's limit of {} bytes",
                limits::MAX_BODY
            ),
        )
    }

    /// The body as text (tests, messages).
    pub fn text(&self) -> &str {
        std::str::from_utf8(&self.body).unwrap_or("(binary)")
    }
}

/// What answers an endpoint: the state and the request body to the job's answer.
type Handler = fn(&State, &[u8]) -> Answer;

/// The API's endpoints: method, path, and what answers it.
const ROUTES: [(&str, &str, Handler); 7] = [
    ("GET", "/api/model", model_info),
    ("POST", "/api/simulate", simulate),
    ("POST", "/api/phase", phase),
    ("POST", "/api/margins", margins),
    ("POST", "/api/lyapunov", lyapunov),
    ("POST", "/api/map", map),
    ("POST", "/api/tune", tune),
];

/// The API's endpoints with their method.
pub fn endpoints() -> impl Iterator<Item = (&'static str, &'static str)> {
    ROUTES.iter().map(|(method, path, _)| (*method, *path))
}

/// Answers one request.
pub fn respond(state: &State, method: &str, url: &str, body: &[u8]) -> Reply {
    let path = url.split(['?', '#']).next().unwrap_or("");
    if let Some(asset) = assets::get(path) {
        return match method {
            "GET" | "HEAD" => Reply {
                status: 200,
                content_type: asset.content_type,
                body: asset.bytes.to_vec(),
            },
            _ => not_allowed(method, path, "GET"),
        };
    }
    let Some((expected, _, handler)) = ROUTES.iter().find(|(_, p, _)| *p == path) else {
        return Reply::error(404, format!("{path}: no such page or endpoint"));
    };
    if method != *expected {
        return not_allowed(method, path, expected);
    }
    let started = Instant::now();
    match handler(state, body) {
        Ok((result, series)) => {
            let ms = started.elapsed().as_secs_f64() * 1e3;
            Reply::json(format!(
                "{{\"server_ms\":{ms:.3},\"result\":{result}{}}}",
                series.map_or(String::new(), |e| format!(",\"series\":{e}"))
            ))
        }
        Err(reply) => reply,
    }
}

fn not_allowed(method: &str, path: &str, allowed: &str) -> Reply {
    Reply::error(405, format!("{method} {path}: use {allowed}"))
}

/// A job's result as JSON and, for a run, its samples (the answer's `"series"`), or the error
/// reply.
type Answer = Result<(String, Option<String>), Reply>;

/// A request body: parameters by IR name, and the job's settings.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Request<S> {
    #[serde(default)]
    params: BTreeMap<String, f64>,
    settings: Option<S>,
}

/// The body read, with the model the parameters make (the server's own, borrowed, without any).
fn request<'a, S: DeserializeOwned>(
    state: &'a State,
    body: &[u8],
) -> Result<(Cow<'a, ResolvedModel>, Option<S>), Reply> {
    let text = if body.iter().all(u8::is_ascii_whitespace) {
        "{}"
    } else {
        std::str::from_utf8(body).map_err(|_| Reply::error(400, "body: not UTF-8".into()))?
    };
    let mut reader = serde_json::Deserializer::from_str(text);
    let r: Request<S> = serde_path_to_error::deserialize(&mut reader).map_err(|e| {
        let path = e.path().to_string();
        let at = if path == "." || path == "?" {
            String::new()
        } else {
            format!(" {path}")
        };
        Reply::error(400, format!("body{at}: {}", e.inner()))
    })?;
    reader
        .end()
        .map_err(|e| Reply::error(400, format!("body: {e}")))?;
    let model = if r.params.is_empty() {
        Cow::Borrowed(&state.model)
    } else {
        let values: Vec<(String, f64)> = r.params.into_iter().collect();
        Cow::Owned(
            state
                .model
                .with_param_values(&values, "the page")
                .map_err(|e| Reply::error(422, e.to_string()))?,
        )
    };
    Ok((model, r.settings))
}

fn refused(reason: limits::Refusal) -> Reply {
    Reply::error(413, reason)
}

fn failed(e: twv_analysis::Error) -> Reply {
    Reply::error(422, e.to_string())
}

fn to_json<T: Serialize>(value: &T) -> Result<String, Reply> {
    serde_json::to_string(value)
        .map_err(|e| Reply::error(422, format!("result cannot be written as JSON: {e}")))
}

/// The model the server runs: its parameters (name, key, unit, value, description), states,
/// inputs, the jobs' default settings and the limits.
fn model_info(state: &State, _body: &[u8]) -> Answer {
    let model = &state.model;
    #[derive(Serialize)]
    struct Param<'a> {
        name: &'a str,
        key: &'a str,
        unit: &'a str,
        value: f64,
        description: &'a str,
    }
    #[derive(Serialize)]
    struct Defaults {
        simulate: SimSettings,
        margins: LinearSettings,
        lyapunov: LyapunovRequest,
        tune: TuneSettings,
    }
    #[derive(Serialize)]
    struct Info<'a> {
        model: &'a str,
        params_origin: &'a str,
        params: Vec<Param<'a>>,
        states: Vec<&'a str>,
        inputs: Vec<&'a str>,
        defaults: Defaults,
        limits: limits::Limits,
    }
    let params = model
        .ir
        .params()
        .iter()
        .zip(&model.params)
        .filter(|(p, _)| p.used)
        .map(|(p, v)| Param {
            name: &p.name,
            key: &p.key,
            unit: &p.unit,
            value: *v,
            description: &p.description,
        })
        .collect();
    let info = Info {
        model: model.name(),
        params_origin: &model.params_origin,
        params,
        states: model.states(),
        inputs: model.inputs(),
        defaults: Defaults {
            simulate: SimSettings::default(),
            margins: LinearSettings::default(),
            lyapunov: LyapunovRequest::default(),
            tune: TuneSettings::default(),
        },
        limits: LIMITS,
    };
    Ok((to_json(&info)?, None))
}

/// The samples of a run by column: `{"t": […], "phi": […], …}`.
fn series(columns: &[String], rows: &[Vec<f64>]) -> Result<String, Reply> {
    let by_column: BTreeMap<&str, Vec<f64>> = columns
        .iter()
        .enumerate()
        .map(|(j, name)| (name.as_str(), rows.iter().map(|r| r[j]).collect()))
        .collect();
    to_json(&by_column)
}

fn simulate(state: &State, body: &[u8]) -> Answer {
    let (model, s) = request::<SimSettings>(state, body)?;
    let s = s.unwrap_or_default();
    limits::simulate(&s).map_err(refused)?;
    let r = api::simulate(&model, &s, &Silent).map_err(failed)?;
    Ok((to_json(&r)?, Some(series(&r.columns, &r.rows)?)))
}

/// A phase portrait of the current controller from several initial tilts.
#[derive(Deserialize)]
#[serde(default, deny_unknown_fields)]
struct PhaseRequest {
    /// The controller. Default the study's PD.
    controller: ControllerSettings,
    /// Initial pitch angles [rad], each from rest. Default ±0.1, ±0.2.
    tilts: Vec<f64>,
    /// Length, sampling and integrator of each run. Default 10 s.
    run: RunSettings,
}

impl Default for PhaseRequest {
    fn default() -> Self {
        Self {
            controller: ControllerSettings::default(),
            tilts: api::DEFAULT_TILTS.to_vec(),
            run: RunSettings::default(),
        }
    }
}

fn phase(state: &State, body: &[u8]) -> Answer {
    let (model, s) = request::<PhaseRequest>(state, body)?;
    let s = s.unwrap_or_default();
    limits::phase(&s.run, &s.tilts).map_err(refused)?;
    let x0 = s
        .tilts
        .iter()
        .map(|&t| model.rest_with("phi", t))
        .collect::<Result<Vec<_>, _>>()
        .map_err(failed)?;
    let settings = PhaseSettings {
        portraits: vec![("current gains".into(), Drive::Closed(s.controller))],
        x0: Some(x0),
        run: s.run,
    };
    let r = api::portraits(&model, &settings, &Silent).map_err(failed)?;
    // The trajectories, which the library's JSON leaves to the CSV: per run, Φ and Φ̇.
    #[derive(Serialize)]
    struct Trajectory<'a> {
        phi0: f64,
        t: &'a [f64],
        phi: Vec<f64>,
        phi_dot: Vec<f64>,
    }
    let runs: Vec<Trajectory> = r.portraits[0]
        .runs
        .iter()
        .map(|run| Trajectory {
            phi0: run.phi0,
            t: &run.t,
            phi: run.points.iter().map(|p| p.0).collect(),
            phi_dot: run.points.iter().map(|p| p.1).collect(),
        })
        .collect();
    Ok((to_json(&r)?, Some(to_json(&runs)?)))
}

fn margins(state: &State, body: &[u8]) -> Answer {
    let (model, s) = request::<LinearSettings>(state, body)?;
    let s = s.unwrap_or_default();
    limits::margins(&s).map_err(refused)?;
    let r = api::analyse(&model, &s).map_err(failed)?;
    Ok((to_json(&r)?, None))
}

/// The largest Lyapunov exponent of the pitch loop at the current controller after a tilt:
/// the map's `max-lyapunov` metric at one point, over a short horizon.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LyapunovRequest {
    /// The controller (its gains are the point). Default the study's PD.
    pub controller: ControllerSettings,
    /// Initial pitch from rest [rad]. Default 0.1.
    pub tilt: f64,
    /// The metric's sampling. Default 1 ms RK4, 30 samples of 0.1 s after 0.5 s.
    pub metric_settings: MetricSettings,
}

impl Default for LyapunovRequest {
    fn default() -> Self {
        Self {
            controller: ControllerSettings::default(),
            tilt: 0.1,
            metric_settings: MetricSettings {
                iterations: 30,
                transient: 0.5,
                ..MetricSettings::default()
            },
        }
    }
}

/// What the short-horizon exponent says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ExponentVerdict {
    /// λ1 < −resolution: nearby trajectories converge.
    Stable,
    /// λ1 > +resolution: they diverge.
    Unstable,
    /// |λ1| ≤ resolution: the horizon is too short to tell.
    Undecided,
    /// |Φ| passed the fall angle.
    Fell,
    /// No value (the integration blew up or failed).
    Failed,
}

/// The exponent with its verdict: `resolution` is one e-fold over the averaging time
/// (1 / (t_sample × iterations)), the smallest rate such a run can tell from zero.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoopExponent {
    pub point: PointResult,
    pub resolution: f64,
    pub verdict: ExponentVerdict,
}

/// The verdict of `point` at `resolution`.
pub fn exponent_verdict(point: &PointResult, resolution: f64) -> ExponentVerdict {
    match (point.status, point.value) {
        (Status::Fell, _) => ExponentVerdict::Fell,
        (Status::Ok, Some(v)) if v < -resolution => ExponentVerdict::Stable,
        (Status::Ok, Some(v)) if v > resolution => ExponentVerdict::Unstable,
        (Status::Ok, Some(_)) => ExponentVerdict::Undecided,
        _ => ExponentVerdict::Failed,
    }
}

fn lyapunov(state: &State, body: &[u8]) -> Answer {
    let (model, s) = request::<LyapunovRequest>(state, body)?;
    let s = s.unwrap_or_default();
    let g = s.controller.pitch.gains;
    let one = |v: f64| Axis { lo: v, hi: v, n: 1 };
    let sweep = SweepSettings {
        grid: Grid {
            kp: one(g.kp),
            kd: one(g.kd),
            ki: (g.ki != 0.0).then(|| one(g.ki)),
            params: Vec::new(),
        },
        metric: Metric::MaxLyapunov,
        x0: None,
        tilt: s.tilt,
        controller: s.controller,
        metric_settings: s.metric_settings,
    };
    limits::map(&sweep, 1).map_err(refused)?;
    let point = api::sweep(&model, &sweep, &Silent).map_err(failed)?[0];
    let m = &s.metric_settings;
    let resolution = 1.0 / (m.t_sample * m.iterations as f64);
    let r = LoopExponent {
        point,
        resolution,
        verdict: exponent_verdict(&point, resolution),
    };
    Ok((to_json(&r)?, None))
}

fn map(state: &State, body: &[u8]) -> Answer {
    let (model, s) = request::<SweepSettings>(state, body)?;
    let s = s.ok_or_else(|| {
        Reply::error(
            400,
            "settings: a map needs at least `grid` and `metric`".into(),
        )
    })?;
    let points = s.config(&model).map_err(failed)?.grid.len();
    limits::map(&s, points).map_err(refused)?;
    let r = api::sweep(&model, &s, &Silent).map_err(failed)?;
    Ok((to_json(&r)?, None))
}

fn tune(state: &State, body: &[u8]) -> Answer {
    let (model, s) = request::<TuneSettings>(state, body)?;
    let s = s.unwrap_or_default();
    limits::tune(&s).map_err(refused)?;
    let r = api::tune_model(&model, &s).map_err(failed)?;
    Ok((to_json(&r)?, None))
}
