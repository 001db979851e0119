//! The live page's JSON API (`twv serve`): every endpoint's numbers are the library's for the
//! same settings, bad and oversized requests get a 4xx with a reason, and the real server over
//! a socket refuses a huge body without reading it and stops when asked.

use std::io::{Read, Write};
use std::net::TcpStream;

use serde_json::{json, Value};
use twv_analysis::api::{self, LinearSettings, Silent, SimSettings, TuneSettings};
use twv_analysis::jobs::{exponent_verdict, ExponentSettings, ExponentVerdict};
use twv_analysis::model::{ModelSpec, ResolvedModel};
use twv_analysis::sweep::{PointResult, Status};
use twv_serve::routes::endpoints;
use twv_serve::{respond, CancelFlag, ServeSettings, Server, State};

fn model() -> ResolvedModel {
    ModelSpec::shipped("vehicle8").resolve().unwrap()
}

fn post(state: &State, path: &str, body: &Value) -> (u16, Value) {
    let reply = respond(state, "POST", path, body.to_string().as_bytes());
    let value = serde_json::from_slice(&reply.body).unwrap();
    (reply.status, value)
}

fn ok(state: &State, path: &str, body: &Value) -> Value {
    let (status, answer) = post(state, path, body);
    assert_eq!(status, 200, "{path}: {answer}");
    assert!(answer["server_ms"].as_f64().unwrap() >= 0.0);
    answer
}

fn error(state: &State, path: &str, body: &[u8], status: u16, needles: &[&str]) {
    let reply = respond(state, "POST", path, body);
    assert_eq!(reply.status, status, "{path}: {}", reply.text());
    let message = serde_json::from_slice::<Value>(&reply.body).unwrap()["error"]
        .as_str()
        .unwrap()
        .to_string();
    for n in needles {
        assert!(message.contains(n), "`{n}` missing from: {message}");
    }
}

fn library<T: serde::Serialize>(value: &T) -> Value {
    serde_json::to_value(value).unwrap()
}

#[test]
fn every_endpoint_gives_the_librarys_numbers() {
    let state = State::new(model());
    let m = model();
    let gains = json!({"kp": 3000.0, "ki": 0.0, "kd": 900.0});
    let controller = json!({"pitch": {"gains": gains, "saturation": 800.0}});

    let sim = json!({"controller": controller, "phi0": 0.2});
    let answer = ok(&state, "/api/simulate", &json!({ "settings": sim }));
    let settings: SimSettings = serde_json::from_value(sim).unwrap();
    let lib = api::simulate(&m, &settings, &Silent).unwrap();
    assert_eq!(answer["result"], library(&lib));
    let phi: Vec<f64> = serde_json::from_value(answer["series"]["phi"].clone()).unwrap();
    let column = lib.columns.iter().position(|c| c == "phi").unwrap();
    assert_eq!(phi, lib.rows.iter().map(|r| r[column]).collect::<Vec<_>>());

    let margins = json!({"gains": gains, "frequency_points": 300});
    let answer = ok(&state, "/api/linearize", &json!({ "settings": margins }));
    let settings: LinearSettings = serde_json::from_value(margins).unwrap();
    let lib = api::analyse(&m, &settings).unwrap();
    assert_eq!(answer["result"], library(&lib));
    assert_eq!(
        answer["result"]["pitch"]["response"]["w"]
            .as_array()
            .unwrap()
            .len(),
        300
    );

    let tune = json!({"spec": "dpm>=40", "tilt": 0.15});
    let answer = ok(&state, "/api/tune", &json!({ "settings": tune }));
    let settings: TuneSettings = serde_json::from_value(tune).unwrap();
    assert_eq!(
        answer["result"],
        library(&api::tune_model(&m, &settings).unwrap())
    );

    let answer = ok(
        &state,
        "/api/phase",
        &json!({"settings": {"portraits": [["current gains", {"closed": controller}]], "tilts": [0.1, -0.3]}}),
    );
    let runs = answer["series"][0].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    assert_eq!(runs[1]["phi0"], json!(-0.3));
    assert_eq!(runs[1]["phi"][0], json!(-0.3));

    // The exponent is the map's metric at that one point, with its verdict.
    let lyap = ok(
        &state,
        "/api/exponent",
        &json!({"settings": {"controller": controller}}),
    );
    let row = json!({
        "grid": {"kp": {"lo": 3000.0, "hi": 3000.0, "n": 1}, "kd": {"lo": 900.0, "hi": 900.0, "n": 1}},
        "metric": "max-lyapunov",
        "controller": controller,
        "metric_settings": library(&ExponentSettings::default().metric_settings),
    });
    let map = ok(&state, "/api/sweep", &json!({ "settings": row }));
    // The old name of the route answers too (an alias of the job).
    assert_eq!(
        ok(&state, "/api/map", &json!({ "settings": row }))["result"],
        map["result"]
    );
    // Flat options, the CLI's and Python's vocabulary, give the same run as the settings.
    let by_options = ok(
        &state,
        "/api/exponent",
        &json!({"options": {"kp": 3000.0, "kd": 900.0, "f_max": 800.0}}),
    );
    assert_eq!(by_options["result"], lyap["result"]);
    assert_eq!(lyap["result"]["point"], map["result"][0]);
    assert_eq!(lyap["result"]["verdict"], json!("stable"));
    assert!(lyap["result"]["point"]["value"].as_f64().unwrap() < 0.0);
}

#[test]
fn parameters_are_set_by_name_and_checked_like_a_file() {
    let state = State::new(model());
    let answer = ok(
        &state,
        "/api/linearize",
        &json!({"params": {"m2": 12.0, "b": 0.7}, "settings": {}}),
    );
    let heavier = model()
        .with_param_values(&[("m2".into(), 12.0), ("b".into(), 0.7)], "the page")
        .unwrap();
    let lib = api::analyse(&heavier, &LinearSettings::default()).unwrap();
    assert_eq!(answer["result"], library(&lib));
    // A heavier, longer pendulum moves the open-loop pole: the parameters reached the model.
    let default = ok(&state, "/api/linearize", &json!({}));
    // The file's keys work too, a component array for an inertia.
    let by_key = ok(
        &state,
        "/api/linearize",
        &json!({"params": {"m2": 12.0, "b": 0.7, "I2": [0.81, 0.81, 0.03]}}),
    );
    assert_eq!(by_key["result"]["open_loop"], answer["result"]["open_loop"]);
    assert_ne!(
        answer["result"]["open_loop"][0],
        default["result"]["open_loop"][0]
    );
    error(
        &state,
        "/api/simulate",
        br#"{"params": {"I2_xx": -1}}"#,
        422,
        &["`I2_xx`", "positive"],
    );
    error(
        &state,
        "/api/simulate",
        br#"{"params": {"mass": 3}}"#,
        422,
        &["unknown parameter `mass`"],
    );
}

#[test]
fn malformed_requests_get_400_with_a_reason() {
    let state = State::new(model());
    error(&state, "/api/simulate", b"{not json", 400, &["body:"]);
    error(
        &state,
        "/api/simulate",
        br#"{"setings": {}}"#,
        400,
        &["unknown field `setings`"],
    );
    error(
        &state,
        "/api/simulate",
        br#"{"settings": {"phi0": "a lot"}}"#,
        422,
        &["phi0", "invalid type"],
    );
    error(
        &state,
        "/api/simulate",
        &[0xff, 0xfe, b'{'],
        400,
        &["UTF-8"],
    );
    // The default map (100 × 100) is more than one request may ask.
    error(&state, "/api/sweep", b"{}", 413, &["points", "limit"]);
    error(
        &state,
        "/api/tune",
        br#"{"settings": {"spec": "dpm>=banana"}}"#,
        422,
        &["spec"],
    );
    error(
        &state,
        "/api/simulate",
        br#"{"options": {"kpp": 1}}"#,
        422,
        &["kpp", "no such option"],
    );
    // Valid JSON the library refuses: 422, naming the field.
    error(
        &state,
        "/api/simulate",
        br#"{"settings": {"run": {"t_end": -1}}}"#,
        422,
        &["t_end"],
    );
    error(
        &state,
        "/api/exponent",
        br#"{"settings": {"controller": {"pitch": {"saturation": -5}}}}"#,
        422,
        &["F_max", "-5"],
    );
    let reply = respond(&state, "GET", "/api/simulate", b"");
    assert_eq!(reply.status, 405, "{}", reply.text());
    assert_eq!(respond(&state, "DELETE", "/", b"").status, 405);
    assert_eq!(respond(&state, "GET", "/etc/passwd", b"").status, 404);
    assert_eq!(respond(&state, "GET", "/../Cargo.toml", b"").status, 404);
    for (method, path) in endpoints() {
        assert_ne!(respond(&state, method, &path, b"").status, 404, "{path}");
    }
    let page = respond(&state, "GET", "/", b"");
    assert_eq!(
        (page.status, page.content_type),
        (200, "text/html; charset=utf-8")
    );
    assert!(page.text().contains("/vendor/chart.umd.min.js"));
}

#[test]
fn oversized_requests_are_refused_before_any_work() {
    let state = State::new(model());
    let cases: [(&str, Value, u16, &[&str]); 11] = [
        (
            "/api/simulate",
            json!({"settings": {"run": {"t_end": 200.0, "sample": 0.1}}}),
            413,
            &["horizon", "limit"],
        ),
        (
            "/api/simulate",
            json!({"settings": {"run": {"t_end": 100.0, "integrator": {"kind": "rk4", "h": 1e-6}}}}),
            413,
            &["steps", "limit"],
        ),
        // More samples than a run may hold at all: the library refuses it, naming the field.
        (
            "/api/simulate",
            json!({"settings": {"run": {"sample": 1e-7}}}),
            422,
            &["samples", "sample interval"],
        ),
        // Fewer, but more than one request may return.
        (
            "/api/simulate",
            json!({"settings": {"run": {"t_end": 100.0, "sample": 1e-3}}}),
            413,
            &["samples", "limit"],
        ),
        // An adaptive run's steps are bounded by its smallest step: none given, no bound.
        (
            "/api/simulate",
            json!({"options": {"integrator": "dopri", "h_max": 1e-8, "t_end": 100}}),
            413,
            &["unbounded", "steps", "h_min"],
        ),
        (
            "/api/phase",
            json!({"settings": {"tilts": vec![0.1; 100]}}),
            413,
            &["samples", "limit"],
        ),
        (
            "/api/exponent",
            json!({"settings": {"tilt": 1e308}}),
            422,
            &["tilt", "half turn"],
        ),
        (
            "/api/simulate",
            json!({"settings": {"phi0": -4.0}}),
            422,
            &["phi0", "half turn"],
        ),
        (
            "/api/linearize",
            json!({"settings": {"frequency_points": 1_000_000}}),
            422,
            &["frequency_points"],
        ),
        (
            "/api/sweep",
            json!({"settings": {"grid": {"kp": {"lo": 0, "hi": 8000, "n": 1000}, "kd": {"lo": 0, "hi": 4000, "n": 1000}}, "metric": "max-lyapunov"}}),
            413,
            &["points", "limit"],
        ),
        (
            "/api/exponent",
            json!({"settings": {"metric_settings": {"h": 1e-3, "t_sample": 0.1, "iterations": 10000000, "transient": 0.0, "t_end": 10.0, "sample": 0.01, "fall_angle": 1.5}}}),
            413,
            &["horizon", "limit"],
        ),
    ];
    for (path, body, status, needles) in cases {
        let started = std::time::Instant::now();
        error(&state, path, body.to_string().as_bytes(), status, needles);
        assert!(started.elapsed().as_secs_f64() < 1.0, "{path} did work");
    }
}
#[test]
fn the_exponent_verdict_follows_the_value_and_its_resolution() {
    let point = |value: Option<f64>, status| PointResult {
        index: 0,
        kp: 1.0,
        ki: 0.0,
        kd: 1.0,
        value,
        status,
        settled_at: None,
    };
    let v = |value, status| exponent_verdict(&point(value, status), 0.5);
    assert_eq!(v(Some(-0.6), Status::Ok), ExponentVerdict::Stable);
    assert_eq!(v(Some(-0.4), Status::Ok), ExponentVerdict::Undecided);
    assert_eq!(v(Some(0.4), Status::Ok), ExponentVerdict::Undecided);
    assert_eq!(v(Some(0.6), Status::Ok), ExponentVerdict::Unstable);
    assert_eq!(v(None, Status::Fell), ExponentVerdict::Fell);
    assert_eq!(v(None, Status::BlewUp), ExponentVerdict::Failed);
    // And on the model: gains below M_x g cannot hold the pendulum up.
    let state = State::new(model());
    let weak = json!({"settings": {"controller": {"pitch": {"gains": {"kp": 300.0, "ki": 0.0, "kd": 900.0}}}}});
    let answer = ok(&state, "/api/exponent", &weak);
    assert_eq!(answer["result"]["verdict"], json!("fell"), "{answer}");
}

fn http(addr: std::net::SocketAddr, request: &[u8]) -> String {
    let mut stream = TcpStream::connect(addr).unwrap();
    stream
        .set_read_timeout(Some(std::time::Duration::from_secs(20)))
        .unwrap();
    stream.write_all(request).unwrap();
    let mut text = String::new();
    let _ = stream.read_to_string(&mut text);
    text
}

#[test]
fn the_server_answers_over_a_socket_refuses_huge_bodies_unread_and_stops() {
    let settings = ServeSettings {
        port: 0,
        ..ServeSettings::default()
    };
    let server = Server::bind(model(), &settings).unwrap();
    let addr = server.addr();
    assert!(addr.ip().is_loopback());
    static STOP: CancelFlag = CancelFlag::new();
    /// Stops the server however the test ends: a failed assertion must not leave the scope
    /// waiting for a server that never stops.
    struct StopOnDrop;
    impl Drop for StopOnDrop {
        fn drop(&mut self) {
            STOP.raise();
        }
    }
    std::thread::scope(|scope| {
        scope.spawn(|| server.run(&STOP));
        let _stop = StopOnDrop;
        let page = http(
            addr,
            b"GET / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n",
        );
        assert!(page.starts_with("HTTP/1.1 200"), "{page}");
        assert!(page.contains("text/html"));
        // 1 GB announced, nothing sent: refused at once, not read.
        let huge = http(
            addr,
            b"POST /api/simulate HTTP/1.1\r\nHost: x\r\nContent-Length: 1000000000\r\nConnection: close\r\n\r\n",
        );
        assert!(huge.starts_with("HTTP/1.1 413"), "{huge}");
        assert!(huge.contains("limit"), "{huge}");
        let body = br#"{"settings": {"phi0": 0.05}}"#;
        let mut request = format!(
            "POST /api/simulate HTTP/1.1\r\nHost: x\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
            body.len()
        )
        .into_bytes();
        request.extend_from_slice(body);
        let sim = http(addr, &request);
        assert!(sim.starts_with("HTTP/1.1 200"), "{sim}");
        assert!(sim.contains("\"recovery\":\"recovered\""), "{sim}");
        STOP.raise();
    });
}

fn post_over_socket(addr: std::net::SocketAddr, path: &str, body: &Value) -> TcpStream {
    let body = body.to_string();
    let mut stream = TcpStream::connect(addr).unwrap();
    stream
        .set_read_timeout(Some(std::time::Duration::from_secs(30)))
        .unwrap();
    let request = format!(
        "POST {path} HTTP/1.1\r\nHost: x\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    stream.write_all(request.as_bytes()).unwrap();
    stream
}

fn answer_of(mut stream: TcpStream) -> String {
    let mut text = String::new();
    let _ = stream.read_to_string(&mut text);
    text
}

/// One job thread, one place in the queue, a time limit: a job past the limit is stopped and
/// answered 413, a job beyond the queue 503 at once, `GET /api/model` answers while jobs run, a
/// job whose client left is cancelled (the next one starts at once), and the server stops
/// within a second with a job running (issue 38).
#[test]
fn heavy_requests_are_queued_limited_in_time_and_cancelled_when_their_client_leaves() {
    use std::time::{Duration, Instant};
    // Times scale with the build: the test command's release build runs a 40 × 40 map in about
    // a second; an unoptimised build about ten times slower.
    let slow = if cfg!(debug_assertions) { 10 } else { 1 };
    let ms = |n: u64| Duration::from_millis(n * slow);
    let limit = ms(400);
    let settings = ServeSettings {
        port: 0,
        workers: 1,
        queue: 1,
        time_limit: limit,
        ..ServeSettings::default()
    };
    let server = Server::bind(model(), &settings).unwrap();
    let addr = server.addr();
    static STOP: CancelFlag = CancelFlag::new();
    struct StopOnDrop;
    impl Drop for StopOnDrop {
        fn drop(&mut self) {
            STOP.raise();
        }
    }
    // Within every budget limit (1 600 points, 1.8e7 steps), but about a second of work (ten in
    // an unoptimised build): longer than the limit.
    let heavy =
        json!({"options": {"kp": "0:8000:40", "kd": "0:4000:40", "metric": "max-lyapunov"}});
    let cheap = json!({});
    std::thread::scope(|scope| {
        let run = scope.spawn(|| server.run(&STOP));
        let _stop = StopOnDrop;
        let started = Instant::now();
        let first = post_over_socket(addr, "/api/sweep", &heavy);
        std::thread::sleep(ms(50));
        let second = post_over_socket(addr, "/api/sweep", &heavy);
        std::thread::sleep(ms(50));
        let third = answer_of(post_over_socket(addr, "/api/sweep", &heavy));
        assert!(third.starts_with("HTTP/1.1 503"), "{third}");
        assert!(
            third.contains("busy") && third.contains("Retry-After"),
            "{third}"
        );
        let asked = Instant::now();
        let info = http(addr, b"GET /api/model HTTP/1.1\r\nHost: x\r\n\r\n");
        assert!(info.starts_with("HTTP/1.1 200"), "{info}");
        assert!(
            asked.elapsed() < Duration::from_secs(1),
            "{:?}",
            asked.elapsed()
        );
        let first = answer_of(first);
        assert!(first.starts_with("HTTP/1.1 413"), "{first}");
        assert!(first.contains("time limit of 0.4 s"), "{first}");
        let took = started.elapsed();
        assert!(
            took >= limit && took < limit + Duration::from_secs(2),
            "{took:?}"
        );
        // The second job ran after the first (its own limit), and was stopped the same way.
        assert!(answer_of(second).starts_with("HTTP/1.1 413"));

        // A client that leaves: its job is cancelled at its next chunk of 64 points, and the
        // next job starts at once (not when the left job would have hit its time limit).
        drop(post_over_socket(addr, "/api/sweep", &heavy));
        std::thread::sleep(ms(50));
        let asked = Instant::now();
        let next = answer_of(post_over_socket(addr, "/api/linearize", &cheap));
        assert!(next.starts_with("HTTP/1.1 200"), "{next}");
        assert!(asked.elapsed() < ms(250), "{:?}", asked.elapsed());

        // Stopping with a job running: the server is gone as soon as the job's chunk under way
        // ends (64 map points: about a second in this unoptimised test build, 0.1 s in release).
        let running = post_over_socket(addr, "/api/sweep", &heavy);
        std::thread::sleep(ms(50));
        let stopping = Instant::now();
        STOP.raise();
        run.join().unwrap();
        assert!(
            stopping.elapsed() < Duration::from_secs(3),
            "{:?}",
            stopping.elapsed()
        );
        let last = answer_of(running);
        assert!(
            last.is_empty() || last.starts_with("HTTP/1.1 503"),
            "{last}"
        );
    });
}
