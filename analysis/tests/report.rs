//! `twv report` end to end: the HTML references every figure, every figure is a well-formed SVG
//! of the size the page states, and results.json carries the expected keys with finite numbers.

use std::path::PathBuf;
use std::process::Command;

fn finite_numbers(v: &serde_json::Value, path: &str, out: &mut Vec<String>) {
    match v {
        serde_json::Value::Number(n) if !n.as_f64().is_some_and(f64::is_finite) => {
            out.push(path.to_string())
        }
        serde_json::Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| finite_numbers(x, &format!("{path}[{i}]"), out)),
        serde_json::Value::Object(o) => o
            .iter()
            .for_each(|(k, x)| finite_numbers(x, &format!("{path}.{k}"), out)),
        _ => {}
    }
}

#[test]
fn quick_report_is_complete_and_consistent() {
    let dir: PathBuf = std::env::temp_dir().join(format!("twv-report-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_twv"))
        .args(["report", "--quick", "--out", dir.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The internal sweep writes to a scratch folder it removes: nothing about it on stderr.
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("shard-"),
        "scratch sweep output leaked:\n{stderr}"
    );
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    let figures: Vec<PathBuf> = std::fs::read_dir(dir.join("figures"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert!(figures.len() >= 10, "{figures:?}");
    for fig in &figures {
        let name = format!("figures/{}", fig.file_name().unwrap().to_string_lossy());
        let svg = std::fs::read_to_string(fig).unwrap();
        let doc = roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{name}: {e}"));
        let root = doc.root_element();
        assert_eq!(root.tag_name().name(), "svg", "{name}");
        let (w, h) = (
            root.attribute("width").unwrap(),
            root.attribute("height").unwrap(),
        );
        let tag = format!("data-file=\"{name}\" data-width=\"{w}\" data-height=\"{h}\"");
        assert!(html.contains(&tag), "the page references {name} at {w}×{h}");
        assert!(w.parse::<u32>().unwrap() > 100 && h.parse::<u32>().unwrap() > 100);
    }
    for section in [
        "1. The model",
        "2. Open-loop Lyapunov",
        "3. Phase",
        "4. Recovery",
        "5. Linear",
        "7. The study",
    ] {
        assert!(html.contains(section), "{section}");
    }
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("results.json")).unwrap()).unwrap();
    for key in [
        "audit_passed",
        "lyapunov_preset",
        "lyapunov_horizons",
        "recovery",
        "linear",
        "tune",
        "closed_loop_lyapunov",
        "wall_time_s",
    ] {
        assert!(results.get(key).is_some(), "results.json lacks {key}");
    }
    assert_eq!(results["audit_passed"], serde_json::Value::Bool(true));
    let preset = &results["lyapunov_preset"];
    for key in [
        "exponents",
        "stderr",
        "sum",
        "mean_trace",
        "kaplan_yorke",
        "classification",
        "t_total",
    ] {
        assert!(preset.get(key).is_some(), "lyapunov_preset.{key}");
    }
    let mut bad = Vec::new();
    for key in [
        "lyapunov_preset",
        "lyapunov_horizons",
        "closed_loop_lyapunov",
    ] {
        finite_numbers(&results[key], key, &mut bad);
    }
    assert!(bad.is_empty(), "non-finite numbers at {bad:?}");
    let sum = preset["sum"].as_f64().unwrap();
    let trace = preset["mean_trace"].as_f64().unwrap();
    assert!(
        (sum - trace).abs() <= 1e-8 * sum.abs().max(1e-3),
        "Σλ = ⟨tr J⟩"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
