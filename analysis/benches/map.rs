//! The study's max-Lyapunov map, run step by step to the end of every horizon and with the
//! settled tail, side by side: wall time, the ratio, and what the shortcut changed (each
//! point's λ1 against `SETTLED_TAIL_TOLERANCE`, the statuses), for each lanes-kernel build this
//! CPU can run. A benchmark, not a test: it asserts no time, but a point moved beyond the
//! tolerance, a changed status, or a build whose map differs in any bit from the baseline
//! build's (run once, untimed, first) is a failed check and exits non-zero.
//!
//! `cargo bench -p twv-analysis --bench map` (release); `TWV_MAP_N=40` for a 40 × 40 map
//! (default 100 × 100: Kp 0–8000, Kd 0–4000), `TWV_MAP_ROUNDS` (default 2) alternating runs.

use std::process::ExitCode;
use std::time::Instant;

use twv_analysis::api::{sweep, Silent, SweepSettings};
use twv_analysis::model::{ModelSpec, ResolvedModel};
use twv_analysis::sweep::{Grid, Metric, MetricSettings, PointResult, SETTLED_TAIL_TOLERANCE};
use twv_kernels::isa::{available, force, Isa};

fn env_number(name: &str, default: usize) -> Result<usize, String> {
    match std::env::var(name) {
        Ok(text) => text
            .parse()
            .ok()
            .filter(|n| *n > 0)
            .ok_or_else(|| format!("{name}={text}: not a positive count")),
        Err(_) => Ok(default),
    }
}

/// One timed run of the map.
fn run(model: &ResolvedModel, settings: &SweepSettings) -> Result<(f64, Vec<PointResult>), String> {
    let start = Instant::now();
    let points = sweep(model, settings, &Silent).map_err(|e| e.to_string())?;
    Ok((start.elapsed().as_secs_f64(), points))
}

/// The largest |Δλ1| over points both runs have a value for, and the points whose status
/// differs.
fn compare(tail: &[PointResult], full: &[PointResult]) -> (f64, usize) {
    let mut largest = 0.0_f64;
    let mut statuses = 0;
    for (a, b) in tail.iter().zip(full) {
        if a.status != b.status {
            statuses += 1;
        }
        if let (Some(x), Some(y)) = (a.value, b.value) {
            largest = largest.max((x - y).abs());
        }
    }
    (largest, statuses)
}

/// Each point's status, λ1 and settling time as bits: what two builds must agree on exactly.
fn bits(points: &[PointResult]) -> Vec<(String, Option<u64>, Option<u64>)> {
    points
        .iter()
        .map(|p| {
            (
                format!("{:?}", p.status),
                p.value.map(f64::to_bits),
                p.settled_at.map(f64::to_bits),
            )
        })
        .collect()
}

fn main() -> ExitCode {
    match bench() {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("map bench: {e}");
            ExitCode::FAILURE
        }
    }
}

fn bench() -> Result<bool, String> {
    // `cargo bench` passes `--bench`; `cargo test --benches` runs it without, as a smoke test.
    let timing = std::env::args().any(|a| a == "--bench");
    let n = env_number("TWV_MAP_N", if timing { 100 } else { 6 })?;
    let rounds = env_number("TWV_MAP_ROUNDS", if timing { 2 } else { 1 })?;
    let model = ModelSpec::shipped("vehicle8")
        .resolve()
        .map_err(|e| e.to_string())?;
    let grid = Grid::study_gains(n);
    let tail = SweepSettings::new(grid, Metric::MaxLyapunov);
    let full = SweepSettings {
        metric_settings: MetricSettings {
            settle_distance: None,
            ..tail.metric_settings
        },
        ..tail.clone()
    };
    println!(
        "{}; {} threads; {n} × {n} max-Lyapunov map of vehicle8 (Kp 0–8000, Kd 0–4000, tilt \
         0.1 rad), {rounds} alternating round(s)",
        twv_analysis::machine::describe(),
        rayon::current_num_threads()
    );
    println!();
    // The reference bits: the baseline build (the one the tests check against one point at a
    // time), untimed.
    force(Isa::Baseline);
    let (_, reference) = run(&model, &tail)?;
    let mut same_bits = true;
    println!("| lanes kernel | every step, s | settled tail, s | ratio | settled points | largest Δλ1, 1/s | statuses changed |");
    println!("|---|---:|---:|---:|---:|---:|---:|");
    let mut passed = true;
    for isa in [Isa::Avx512, Isa::Avx2, Isa::Neon] {
        if !available(isa) {
            println!("| {} | not run: this CPU lacks it | | | | | |", isa.name());
            continue;
        }
        let used = force(isa);
        let (mut t_full, mut t_tail) = (f64::INFINITY, f64::INFINITY);
        let (mut p_full, mut p_tail) = (Vec::new(), Vec::new());
        for _ in 0..rounds {
            let (t, p) = run(&model, &full)?;
            (t_full, p_full) = (t_full.min(t), p);
            let (t, p) = run(&model, &tail)?;
            (t_tail, p_tail) = (t_tail.min(t), p);
        }
        let (largest, statuses) = compare(&p_tail, &p_full);
        let settled = p_tail.iter().filter(|p| p.settled_at.is_some()).count();
        println!(
            "| {} | {t_full:.2} | {t_tail:.2} | {:.2} | {settled} of {} | {largest:.1e} | {statuses} |",
            used.name(),
            t_full / t_tail,
            p_tail.len()
        );
        passed &= largest <= SETTLED_TAIL_TOLERANCE && statuses == 0;
        same_bits &= bits(&p_tail) == bits(&reference);
    }
    force(Isa::Avx512);
    passed &= same_bits;
    println!();
    println!(
        "times: the best of the rounds; check: every λ1 within {SETTLED_TAIL_TOLERANCE:e} /s of \
         the full run, no status changed, and every build's map (settled tail) has the bits of \
         the baseline build's — {}",
        if passed { "held" } else { "FAILED" }
    );
    if !same_bits {
        println!("a build's map differs in some bit from the baseline build's");
    }
    Ok(passed)
}
