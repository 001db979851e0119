//! Every job's JSON settings and flat options, as the HTTP API and the JSON runner take them:
//! the first byte picks a job of the registry, the rest is the request body. Settings are
//! refused with one line naming a field, or accepted with a finite budget; accepted settings of
//! a small budget run to a result or an error (never a panic, a NaN in the summary, a hang),
//! and through the server's route (`POST /api/<job>`) to a status and a JSON answer.
#![no_main]
#![deny(warnings)]

use std::sync::OnceLock;

mod common;

use common::vehicle8;
use libfuzzer_sys::fuzz_target;
use serde_json::Value;
use twv_analysis::api::Silent;
use twv_analysis::jobs::{registry, Budget};

fn state() -> &'static twv_serve::State {
    static STATE: OnceLock<twv_serve::State> = OnceLock::new();
    STATE.get_or_init(|| twv_serve::State::new(vehicle8().clone()))
}

/// Work a fuzzer can afford to run (a few milliseconds).
fn small(b: &Budget) -> bool {
    b.horizon <= 5.0
        && b.steps <= 2e4
        && b.samples <= 1e3
        && b.points <= 4.0
        && b.frequency_points <= 200.0
        && b.iterations <= 10.0
}

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else {
        return;
    };
    let jobs: Vec<_> = registry()
        .iter()
        .copied()
        .filter(|j| !matches!(j.name(), "codegen" | "audit"))
        .collect();
    let job = jobs[pick as usize % jobs.len()];
    let Ok(value) = serde_json::from_slice::<Value>(body) else {
        return;
    };
    let model = vehicle8();
    let prepared = match value.get("options").and_then(Value::as_object) {
        Some(options) => {
            let given: Vec<(String, Value)> = options
                .iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect();
            job.prepare_options(value.get("settings"), &given)
        }
        None => job.prepare_json(&value),
    };
    match prepared {
        Err(e) => {
            let line = twv_analysis::error::one_line(&e);
            assert!(!line.is_empty() && !line.contains('\n'), "{line:?}");
        }
        Ok(prepared) => {
            let Ok(budget) = prepared.budget(model) else {
                return;
            };
            assert!(
                !budget.steps.is_nan() && !budget.points.is_nan(),
                "{budget:?}"
            );
            if small(&budget) {
                if let Ok(done) = prepared.run(model, &Silent) {
                    done.json().expect("a result writes as JSON");
                    let summary = done.summary();
                    assert!(!summary.contains("NaN"), "{summary}");
                }
                // The same body through the HTTP route: a status and a JSON answer.
                if job.served() {
                    let path = format!("/api/{}", job.name());
                    let reply = twv_serve::respond(state(), "POST", &path, body);
                    assert!(
                        matches!(reply.status, 200 | 400 | 413 | 422),
                        "{}",
                        reply.status
                    );
                    let answer: Value = serde_json::from_slice(&reply.body).expect("JSON");
                    assert!(answer.get("result").is_some() || answer.get("error").is_some());
                }
            }
        }
    }
    if job.served() {
        let reply = twv_serve::respond(state(), "GET", &format!("/api/{}", job.name()), body);
        assert_eq!(reply.status, 405);
    }
});
