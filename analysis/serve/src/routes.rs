//! The JSON API and the page's files: a request (method, path, body) to a [`Reply`], with no
//! socket involved, so that tests call it directly.
//!
//! Every job of the library's registry that the server offers answers `POST /api/<job>` (its
//! name or an alias): one loop, no route of its own. The body is `{"params": {NAME: VALUE, …},
//! "settings": {…}, "options": {…}}` (all optional): `params` sets vehicle parameters by file
//! key (`I2: [Ixx, Iyy, Izz]`) or IR name (`I2_yy`), checked like a parameter file's values;
//! `settings` is the job's settings type of the library, read by serde with its defaults;
//! `options` are the job's flat options (the CLI's flags, Python's keywords) laid over them.
//! Before a job runs, its budget (steps, samples, points) is held against the server's limits. The answer is
//! `{"server_ms": …, "result": …}`, `result` being the library's result serialised as
//! `twv <job> --json` prints it (a simulation adds `"series"`, its samples by column). Errors
//! are `{"error": "…"}` with 400 (malformed), 404, 405, 413 (body or work over a limit) or 422
//! (refused by the library's validation, or the run failed).

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::time::Instant;

use serde::{Deserialize, Serialize};
use serde_json::Value;
use twv_analysis::api::{Progress, Silent};
use twv_analysis::jobs::{self, AnyJob};
use twv_analysis::model::ResolvedModel;

use crate::assets;
use crate::limits;

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

/// Answers one request (a job never cancelled).
pub fn respond(state: &State, method: &str, url: &str, body: &[u8]) -> Reply {
    respond_with(state, method, url, body, &Silent)
}

/// Whether the request runs a job (`POST /api/<job>` of a served job): the server queues
/// these for its job threads and answers everything else at once.
pub fn is_job(method: &str, url: &str) -> bool {
    let path = url.split(['?', '#']).next().unwrap_or("");
    method == "POST" && path.strip_prefix("/api/").and_then(served).is_some()
}

/// Answers one request; a job looks at `progress` for a cancellation, and a cancelled job
/// answers 503.
pub fn respond_with(
    state: &State,
    method: &str,
    url: &str,
    body: &[u8],
    progress: &dyn Progress,
) -> Reply {
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
    let started = Instant::now();
    let answer = if path == "/api/model" {
        if method != "GET" {
            return not_allowed(method, path, "GET");
        }
        model_info(state)
    } else {
        let Some(job) = path.strip_prefix("/api/").and_then(served) else {
            return Reply::error(404, format!("{path}: no such page or endpoint"));
        };
        if method != "POST" {
            return not_allowed(method, path, "POST");
        }
        run_job(state, job, body, progress)
    };
    match answer {
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

/// The job a route names (by its name or an alias), if the server offers it.
fn served(name: &str) -> Option<&'static dyn AnyJob> {
    jobs::find(name).ok().filter(|j| j.served())
}

/// The API's endpoints with their method: `GET /api/model` and `POST /api/<job>` for every job
/// of the registry the server offers.
pub fn endpoints() -> impl Iterator<Item = (&'static str, String)> {
    std::iter::once(("GET", "/api/model".to_string())).chain(
        jobs::registry()
            .iter()
            .filter(|j| j.served())
            .map(|j| ("POST", format!("/api/{}", j.name()))),
    )
}

fn not_allowed(method: &str, path: &str, allowed: &str) -> Reply {
    Reply::error(405, format!("{method} {path}: use {allowed}"))
}

/// A job's result as JSON and, for a run, its samples (the answer's `"series"`), or the error
/// reply.
type Answer = Result<(String, Option<String>), Reply>;

/// A request body: parameters (by file key or IR name), the job's settings, and its flat
/// options laid over them (the CLI's and Python's vocabulary).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Request {
    #[serde(default)]
    params: BTreeMap<String, ParamValue>,
    settings: Option<Value>,
    #[serde(default)]
    options: serde_json::Map<String, Value>,
}

/// A parameter's value: a number, or the components of a file key (`I2: [Ixx, Iyy, Izz]`).
#[derive(Deserialize)]
#[serde(untagged)]
enum ParamValue {
    One(f64),
    Components(Vec<f64>),
}

/// The body read, with the model the parameters make (the server's own, borrowed, without any).
fn request<'a>(state: &'a State, body: &[u8]) -> Result<(Cow<'a, ResolvedModel>, Request), Reply> {
    let text = if body.iter().all(u8::is_ascii_whitespace) {
        "{}"
    } else {
        std::str::from_utf8(body).map_err(|_| Reply::error(400, "body: not UTF-8".into()))?
    };
    let mut reader = serde_json::Deserializer::from_str(text);
    let r: Request = serde_path_to_error::deserialize(&mut reader).map_err(|e| {
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
        let values: Vec<(String, Vec<f64>)> = r
            .params
            .iter()
            .map(|(k, v)| {
                let v = match v {
                    ParamValue::One(x) => vec![*x],
                    ParamValue::Components(c) => c.clone(),
                };
                (k.clone(), v)
            })
            .collect();
        Cow::Owned(
            state
                .model
                .with_overrides(&values, "the page")
                .map_err(|e| Reply::error(422, e.to_string()))?,
        )
    };
    Ok((model, r))
}

fn failed(e: twv_analysis::Error) -> Reply {
    if e.is_interrupted() {
        return Reply::error(503, "the job was cancelled".into());
    }
    let text = twv_analysis::error::one_line(&e);
    match e {
        twv_analysis::Error::Input { .. } => Reply::error(422, format!("settings: {text}")),
        _ => Reply::error(422, text),
    }
}

/// Runs `job` as the body asks, within the server's limits.
fn run_job(
    state: &State,
    job: &'static dyn AnyJob,
    body: &[u8],
    progress: &dyn Progress,
) -> Answer {
    let (model, r) = request(state, body)?;
    let options: Vec<(String, Value)> = r.options.into_iter().collect();
    let prepared = if options.is_empty() {
        job.prepare_json(
            r.settings
                .as_ref()
                .unwrap_or(&Value::Object(Default::default())),
        )
    } else {
        job.prepare_options(r.settings.as_ref(), &options)
    }
    .map_err(failed)?;
    let budget = prepared.budget(&model).map_err(failed)?;
    limits::check(&budget).map_err(|why| Reply::error(413, why))?;
    let done = prepared.run(&model, progress).map_err(failed)?;
    let result = to_json(&done.value().map_err(failed)?)?;
    let series = done.series().map(|s| s.to_string());
    Ok((result, series))
}

/// The model the server runs: its parameters (name, key, unit, value, description), states and
/// inputs with their units, every served job's default settings and options, and the limits.
fn model_info(state: &State) -> Answer {
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
    struct JobInfo {
        name: &'static str,
        aliases: &'static [&'static str],
        summary: &'static str,
        options: Vec<jobs::OptionInfo>,
    }
    #[derive(Serialize)]
    struct Info<'a, V: Serialize> {
        model: &'a str,
        params_origin: &'a str,
        params: Vec<Param<'a>>,
        states: Vec<&'a str>,
        inputs: Vec<&'a str>,
        state_info: &'a [V],
        input_info: &'a [V],
        defaults: BTreeMap<&'static str, Value>,
        jobs: Vec<JobInfo>,
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
    let served: Vec<&dyn AnyJob> = jobs::registry()
        .iter()
        .copied()
        .filter(|j| j.served())
        .collect();
    let info = Info {
        model: model.name(),
        params_origin: &model.params_origin,
        params,
        states: model.states(),
        inputs: model.inputs(),
        state_info: model.ir.states(),
        input_info: model.ir.inputs(),
        defaults: served
            .iter()
            .map(|j| (j.name(), j.default_settings()))
            .collect(),
        jobs: served
            .iter()
            .map(|j| JobInfo {
                name: j.name(),
                aliases: j.aliases(),
                summary: j.summary(),
                options: j.options(),
            })
            .collect(),
        limits: limits::LIMITS,
    };
    to_json(&info).map(|t| (t, None))
}

fn to_json<T: Serialize>(value: &T) -> Result<String, Reply> {
    serde_json::to_string(value)
        .map_err(|e| Reply::error(422, format!("result cannot be written as JSON: {e}")))
}
