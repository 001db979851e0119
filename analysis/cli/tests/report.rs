//! `twv report` end to end: the page opens with the computed findings, references every figure
//! (SVG with a PNG beside it) at its own size, results.json carries the results with finite
//! numbers, a failed check makes the run exit 3 after writing, and the findings follow the
//! vehicle (a pendulum below its hinge is not reported as recovering).

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{negative_with, twv};

/// Every number in `v` at a path: serde_json writes NaN and ±∞ as null, so a null where the
/// report promises a number is a defect too; `allowed_null` names the fields that may be null.
fn non_finite(v: &serde_json::Value, path: &str, out: &mut Vec<String>) {
    match v {
        serde_json::Value::Number(n) if !n.as_f64().is_some_and(f64::is_finite) => {
            out.push(path.to_string())
        }
        serde_json::Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| non_finite(x, &format!("{path}[{i}]"), out)),
        serde_json::Value::Object(o) => o
            .iter()
            .for_each(|(k, x)| non_finite(x, &format!("{path}.{k}"), out)),
        _ => {}
    }
}

fn report(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["report", "--quick", "--out", dir.to_str().unwrap()];
    args.extend_from_slice(extra);
    twv(&args)
}

fn results(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("results.json")).unwrap()).unwrap()
}

fn scratch(name: &str) -> common::Scratch {
    common::scratch_path("report", name)
}

#[test]
fn quick_report_is_complete_and_consistent() {
    let dir = scratch("ok");
    let out = report(&dir, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    // The summary comes first, before any section.
    let summary = html.find("Summary of findings").expect("a summary");
    assert!(summary < html.find("1. The model").unwrap());
    assert!(!html.contains("check(s) FAILED"));
    let svgs: Vec<PathBuf> = std::fs::read_dir(dir.join("figures"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "svg"))
        .collect();
    assert!(svgs.len() >= 8, "{svgs:?}");
    for fig in &svgs {
        let name = format!("figures/{}", fig.file_name().unwrap().to_string_lossy());
        let svg = std::fs::read_to_string(fig).unwrap();
        let doc = roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{name}: {e}"));
        let root = doc.root_element();
        assert_eq!(root.tag_name().name(), "svg", "{name}");
        let (w, h) = (
            root.attribute("width").unwrap().parse::<u32>().unwrap(),
            root.attribute("height").unwrap().parse::<u32>().unwrap(),
        );
        let tag = format!("data-file=\"{name}\" data-width=\"{w}\" data-height=\"{h}\"");
        assert!(html.contains(&tag), "the page references {name} at {w}×{h}");
        // Shown at its own size on a page about 1100 px wide: text stays ≥ 10 px when the
        // figure is at most 1.2 × that wide (fonts are ≥ 13 px at the declared size).
        assert!(w > 100 && h > 100 && w <= 1320, "{name}: {w}×{h}");
        // Drawn at 4× and declared at 1× (smooth lines), or a composite of such figures.
        let vb = root.attribute("viewBox").unwrap();
        assert!(
            vb.ends_with(&format!("{} {}", 4 * w, 4 * h)) || vb.ends_with(&format!("{w} {h}")),
            "{name}: {vb}"
        );
        // A PNG beside it, at twice the declared size.
        let png = fig.with_extension("png");
        let bytes = std::fs::read(&png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
        assert_eq!(&bytes[1..4], b"PNG", "{}", png.display());
        let width = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
        assert_eq!(width, 2 * w, "{}", png.display());
    }
    for section in [
        "1. The model",
        "2. Open-loop Lyapunov",
        "3. Phase",
        "4. Recovery",
        "5. Linear",
        "6. Stability map",
        "7. Balancing the bicycle",
        "8. The study",
    ] {
        assert!(html.contains(section), "{section}");
    }
    let r = results(&dir);
    for key in [
        "passed",
        "checks",
        "findings",
        "claims",
        "audit",
        "lyapunov_preset",
        "lyapunov_horizons",
        "phase",
        "recovery",
        "linear",
        "tune",
        "map",
        "closed_loop_lyapunov",
        "wall_time_s",
    ] {
        assert!(r.get(key).is_some(), "results.json lacks {key}");
    }
    assert_eq!(r["passed"], true);
    let mut bad = Vec::new();
    for key in [
        "lyapunov_preset",
        "lyapunov_horizons",
        "closed_loop_lyapunov",
        "recovery",
    ] {
        non_finite(&r[key], key, &mut bad);
    }
    assert!(bad.is_empty(), "non-finite numbers at {bad:?}");
    let sum = r["lyapunov_preset"]["sum"].as_f64().unwrap();
    let trace = r["lyapunov_preset"]["mean_trace"].as_f64().unwrap();
    assert!(
        (sum - trace).abs() <= 1e-8 * sum.abs().max(1e-3),
        "Σλ = ⟨tr J⟩"
    );
    // The sentences of the page are the findings of results.json, not literals.
    for f in r["findings"].as_array().unwrap() {
        let text = f["text"].as_str().unwrap();
        let escaped = text
            .replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;");
        assert!(html.contains(&escaped), "the page states: {text}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A check that fails is shown at the top of the page and makes the run exit 3, after the
/// report is written (an audit tolerance below round-off fails the audit).
#[test]
fn a_failed_check_is_at_the_top_and_fails_the_run() {
    let dir = scratch("failed");
    let out = report(&dir, &["--audit-tolerance", "1e-30"]);
    negative_with(&out, &["check(s) failed", "hand model"]);
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    let failed = html.find("check(s) FAILED").expect("the failure box");
    assert!(failed < html.find("Summary of findings").unwrap());
    assert_eq!(results(&dir)["passed"], false);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A pendulum below its hinge (b < 0) under the study's PD: every verdict follows the data —
/// the loop is unstable, the vehicle falls, the claims are not reproduced — and the page says
/// nothing of a recovery in 3 s.
#[test]
fn findings_follow_the_vehicle() {
    let dir = scratch("below");
    std::fs::create_dir_all(&dir).unwrap();
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(repo.join("vehicles/paper.toml")).unwrap();
    let params = dir.join("below.toml");
    std::fs::write(&params, text.replace("b = 0.55 ", "b = -0.55")).unwrap();
    let out_dir = dir.join("report");
    let out = report(&out_dir, &["--params", params.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "no check fails: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = results(&out_dir);
    let verdict = |topic: &str| -> Vec<String> {
        r["findings"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|f| f["topic"] == topic)
            .map(|f| f["verdict"].as_str().unwrap().to_string())
            .collect()
    };
    assert_eq!(verdict("linear pitch loop"), ["unstable"]);
    assert_eq!(verdict("tilt recovery"), ["falls", "falls"]);
    assert_ne!(verdict("tuned gains"), ["met"]);
    let claims: Vec<&str> = r["claims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["verdict"].as_str().unwrap())
        .collect();
    assert_eq!(claims[2], "Not reproduced", "{claims:?}");
    let html = std::fs::read_to_string(out_dir.join("index.html")).unwrap();
    assert!(!html.contains("recovers"), "no recovery claimed");
    std::fs::remove_dir_all(&dir).unwrap();
}
