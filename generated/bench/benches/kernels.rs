//! `cargo bench -p twv-bench`: the generated vehicle8 kernels against CasADi's own generated C
//! (gcc -O3, built by this crate's build script), timed side by side in the same run; then the
//! lanes kernel, the dependent chains that bound the study's Lyapunov preset from below, and
//! the preset itself beside them, for each build this CPU runs (which must all give the preset
//! the same bits: a failed check, exit non-zero).
//!
//! A hand-written harness instead of criterion/divan: six paired measurements need no
//! statistics framework, and the workspace builds (clippy, tests) stay free of its dependencies.
//! A benchmark, not a test: it prints numbers and asserts no time.

use std::hint::black_box;
use std::process::ExitCode;

use twv_analysis::api::{spectrum, Silent, SpectrumSettings};
use twv_analysis::lyapunov::LyapunovSettings;
use twv_analysis::model::{ModelSpec, ResolvedModel};
use twv_baked_paper as baked;
use twv_bench::{
    against_goal, compare, gate, hand_gate, same_bits, time, Casadi, Pair, Plan, Point, Run, Twv,
    K, NNZ, NX, OPS,
};
use twv_generated::Vehicle8;
use twv_model::Model;

/// One row of the table: twv and CasADi's C for one function and parameter mode.
fn measure(plan: Plan, function: &str, twv: &impl Twv, c: &Casadi, pt: &Point) -> Pair {
    match function {
        "f" => compare(
            plan,
            || {
                let mut out = [0.0; NX];
                black_box(twv).f(black_box(&pt.x), black_box(&pt.u), &mut out);
                black_box(&mut out);
            },
            || {
                let mut out = [0.0; NX];
                black_box(c).f(black_box(&pt.x), black_box(&pt.u), &mut out);
                black_box(&mut out);
            },
        ),
        "f+jac_x" => compare(
            plan,
            || {
                let mut f = [0.0; NX];
                let mut j = black_box(twv).f_jac_x(black_box(&pt.x), black_box(&pt.u), &mut f);
                black_box((&mut f, &mut j));
            },
            || {
                let (mut f, mut j) = ([0.0; NX], [0.0; NNZ]);
                black_box(c).f_jac_x(black_box(&pt.x), black_box(&pt.u), &mut f, &mut j);
                black_box((&mut f, &mut j));
            },
        ),
        _ => compare(
            plan,
            || {
                let (mut f, mut out) = ([0.0; NX], [[0.0; NX]; K]);
                black_box(twv).f_jw::<K>(
                    black_box(&pt.x),
                    black_box(&pt.u),
                    black_box(&pt.w),
                    &mut f,
                    &mut out,
                );
                black_box((&mut f, &mut out));
            },
            || {
                let (mut f, mut out) = ([0.0; NX], [[0.0; NX]; K]);
                black_box(c).f_jw8(
                    black_box(&pt.x),
                    black_box(&pt.u),
                    black_box(&pt.w),
                    &mut f,
                    &mut out,
                );
                black_box((&mut f, &mut out));
            },
        ),
    }
}

/// The table of every kernel, runtime and baked, against a C peer's `[runtime, baked]` builds.
fn peer_table(
    plan: Plan,
    pt: &Point,
    (name, short): (&str, &str),
    [c_runtime, c_baked]: [&Casadi; 2],
    runtime: &Vehicle8,
) {
    println!("| function | params | twv ns | {name} ns | ratio (twv/{short}) |");
    println!("|---|---|---:|---:|---:|");
    for function in ["f", "f+jac_x", "f_jw (K=8)"] {
        for params in ["runtime", "baked"] {
            let pair = match params {
                "runtime" => measure(plan, function, runtime, c_runtime, pt),
                _ => measure(plan, function, &baked::Vehicle8, c_baked, pt),
            };
            println!(
                "| {function} | {params} | {} | {} | {:.2} |",
                pair.twv, pair.c, pair.ratio.median
            );
        }
    }
}

fn main() -> ExitCode {
    // `cargo bench` passes `--bench`; `cargo test --benches` passes no `--bench` and only
    // wants to know that the target runs: then check correctness and stop.
    let timing = std::env::args().any(|a| a == "--bench");
    if let Err(e) = gate(1000) {
        eprintln!("twv-bench: the Rust kernels and CasADi's C disagree, nothing timed:\n{e}");
        return ExitCode::FAILURE;
    }
    if let Err(e) = hand_gate(1000) {
        eprintln!("twv-bench: the Rust kernels and the hand formulation disagree:\n{e}");
        return ExitCode::FAILURE;
    }
    println!(
        "correctness gate passed: f, jac_x and J·W within 1e-13 of the size of their terms \
         (1001 points); the hand formulation's C within 1e-11 of each quantity's size"
    );
    if !timing {
        return ExitCode::SUCCESS;
    }

    let plan = match Plan::from_env() {
        Ok(plan) => plan,
        Err(e) => {
            eprintln!("twv-bench: {e}");
            return ExitCode::FAILURE;
        }
    };
    let pt = Point::bench();
    let runtime = Vehicle8::with_defaults();
    let (c_runtime, c_baked) = match (Casadi::runtime(Vehicle8::DEFAULTS), Casadi::baked()) {
        (Ok(r), Ok(b)) => (r, b),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("twv-bench: {e}");
            return ExitCode::FAILURE;
        }
    };
    println!(
        "vehicle8, {} samples of >= {} ms per function, paired (twv, C) samples; \
         ns per call: median ±half the interquartile range; {}",
        plan.samples,
        plan.sample_time.as_millis(),
        twv_analysis::machine::describe()
    );
    println!();
    peer_table(
        plan,
        &pt,
        ("CasADi C", "C"),
        [&c_runtime, &c_baked],
        &runtime,
    );
    // The second peer: the same physics written by hand in CasADi (Cramer's rule on the mass
    // matrix's two 2x2 blocks, cse), what a careful user gets without twv.
    let (h_runtime, h_baked) = match (
        Casadi::hand_runtime(Vehicle8::DEFAULTS),
        Casadi::hand_baked(),
    ) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("twv-bench: {e}");
            return ExitCode::FAILURE;
        }
    };
    println!();
    println!(
        "operations after CSE (f, f+jac_x, f_jw8): twv's derivation {}; the hand formulation {}",
        OPS[0].trim(),
        OPS[1].trim()
    );
    println!();
    peer_table(
        plan,
        &pt,
        ("hand-formulation C", "hand C"),
        [&h_runtime, &h_baked],
        &runtime,
    );

    // The same kernels with the better builds switched off: what a CPU with only AVX2, or only
    // the x86-64 baseline, gets (and how much of the ratio is the run-time choice of ISA).
    use twv_kernels::isa::{best, force, Isa};
    let top = best();
    for lower in [Isa::Avx2, Isa::Baseline] {
        if lower >= top {
            continue;
        }
        force(lower);
        println!();
        println!(
            "the same, runtime parameters, kernels limited to the {} build:",
            lower.name()
        );
        println!();
        println!(
            "| function | twv ns | CasADi C ns | ratio (twv/C) | hand C ns | ratio (twv/hand C) |"
        );
        println!("|---|---:|---:|---:|---:|---:|");
        for function in ["f", "f+jac_x", "f_jw (K=8)"] {
            let pair = measure(plan, function, &runtime, &c_runtime, &pt);
            let hand = measure(plan, function, &runtime, &h_runtime, &pt);
            println!(
                "| {function} | {} | {} | {:.2} | {} | {:.2} |",
                pair.twv, pair.c, pair.ratio.median, hand.c, hand.ratio.median
            );
        }
        force(top);
    }
    println!();
    println!(
        "(this CPU's best build: {}; builds above it could not run here)",
        top.name()
    );

    // What each side pays per angle: CasADi's C calls the C library's sin and cos (gcc merges
    // them into one sincos call); the Rust kernels inline twv_kernels::trig::sin_cos.
    let libm = time(plan, || {
        let (s, c) = black_box(pt.x[0]).sin_cos();
        black_box((s, c));
    });
    let inline = time(plan, || {
        let (s, c) = twv_kernels::trig::sin_cos(black_box(pt.x[0]));
        black_box((s, c));
    });
    println!();
    println!(
        "reference, sin and cos of one angle: C library {libm} ns, twv_kernels::trig {inline} ns"
    );

    // What a map over many grid points pays per point for its closed-loop stage (one tangent
    // vector and ∂f/∂u): one point per call, or eight lanes per call.
    let one = time(plan, || {
        let (mut f, mut out, mut ju) = ([0.0; NX], [[0.0; NX]; 1], [[0.0; 2]; NX]);
        black_box(&runtime).f_jw_jac_u::<1>(
            black_box(&pt.x),
            black_box(&pt.u),
            black_box(&[pt.w[0]]),
            &mut f,
            &mut out,
            &mut ju,
        );
        black_box((&mut f, &mut out, &mut ju));
    });
    const L: usize = twv_kernels::lanes::LANES;
    let lanes = || {
        time(plan, || {
            let (x, u, w) = ([pt.x; L], [pt.u; L], [pt.w[0]; L]);
            let (mut f, mut out, mut ju) = ([[0.0; NX]; L], [[0.0; NX]; L], [[[0.0; 2]; NX]; L]);
            black_box(&runtime).f_jw_jac_u_lanes(
                black_box(&x),
                black_box(&u),
                black_box(&w),
                &mut f,
                &mut out,
                &mut ju,
            );
            black_box((&mut f, &mut out, &mut ju));
        })
    };
    // The same on lane arrays (entry-major), the form the maps' driver keeps its points in:
    // no transposes in or out.
    let arrays = || {
        time(plan, || {
            let (x, u) = (
                twv_kernels::lanes::gather(&[pt.x; L]),
                [[pt.u[0]; L], [pt.u[1]; L]],
            );
            let w = twv_kernels::lanes::gather(&[pt.w[0]; L]);
            let (mut f, mut out, mut ju) = ([[0.0; L]; NX], [[0.0; L]; NX], [[[0.0; L]; 2]; NX]);
            black_box(&runtime).f_jw_jac_u_lane_arrays(
                black_box(&x),
                black_box(&u),
                black_box(&w),
                &mut f,
                &mut out,
                &mut ju,
            );
            black_box((&mut f, &mut out, &mut ju));
        })
    };
    println!();
    println!(
        "closed-loop stage kernel (f, J·w for one w, ∂f/∂u): one point per call {one} ns; \
         {L} lanes per call (one array per point | lane arrays, as the maps call it), each build \
         this CPU can run:"
    );
    each_build(|isa| {
        let (t, a) = (lanes(), arrays());
        println!(
            "  {}: {t} ns | {a} ns ({:.1} | {:.1} ns per point, {:.2}× | {:.2}× one point per \
             call)",
            isa.name(),
            t.median / L as f64,
            a.median / L as f64,
            one.median * L as f64 / t.median,
            one.median * L as f64 / a.median
        );
    });

    // The Lyapunov floor: an RK4 stage cannot start before the previous stage's f is known, so
    // the study preset (10 s at h = 1e-3: 40 000 stages) costs at least 40 000 times the
    // latency of one dependent f call even without tangent vectors, and in practice that of
    // f_jw, whatever the integrator around it does.
    println!();
    println!("dependent chains (each call waits for the previous result), runtime parameters:");
    let preset = match Preset::new() {
        Ok(preset) => preset,
        Err(e) => {
            eprintln!("twv-bench: the study's preset: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut spectra: Vec<Run> = Vec::new();
    each_build(|isa| {
        let mut x = pt.x;
        let f_latency = time(plan, || {
            let mut f = [0.0; NX];
            runtime.f(&x, &pt.u, &mut f);
            // Feed the result back at a scale that leaves the point unchanged in practice.
            x[0] += 1e-300 * f[4];
        });
        // The f_jw chain, paired sample by sample with the preset itself (as `twv lyap
        // --preset paper` runs it) so that a slow phase of the machine hits both and largely
        // cancels in their ratio.
        let mut state = pt;
        let mut exponents = Err(String::from("not run"));
        let pair = compare(
            plan,
            || exponents = preset.run(),
            || {
                let (mut f, mut out) = ([0.0; NX], [[0.0; NX]; K]);
                runtime.f_jw::<K>(&state.x, &state.u, &state.w, &mut f, &mut out);
                state.x[0] += 1e-300 * (f[4] + out[7][4]);
                state.w[0][0] += 1e-300 * out[0][5];
            },
        );
        for (what, stats) in [("f", f_latency), ("f_jw (K=8)", pair.c)] {
            println!(
                "  {} build, {what}: {stats} ns per call; 40 000 calls (the study's Lyapunov \
                 preset) {:.2} ms",
                isa.name(),
                stats.median * 40_000.0 / 1e6
            );
        }
        if exponents.is_ok() {
            let ratio = pair.ratio.median / 40_000.0;
            println!(
                "  {} build, the preset's spectrum itself: {:.2} ms ±{:.1}% per run, \
                 {ratio:.2}× the f_jw chain ({} the goal of ≤ {PRESET_GOAL}×)",
                isa.name(),
                pair.twv.median / 1e6,
                pair.twv.spread_percent(),
                against_goal(ratio, PRESET_GOAL)
            );
        }
        spectra.push((isa.name(), exponents));
    });
    // Every build must give the preset the same spectrum, bit for bit.
    match same_bits("the preset's spectrum", &spectra) {
        Ok(line) => {
            println!("{line}");
            ExitCode::SUCCESS
        }
        Err(line) => {
            println!("{line}");
            ExitCode::FAILURE
        }
    }
}

/// The goal for the study preset: its spectrum within 1.2× the chain of 40 000 dependent f_jw
/// calls it cannot run faster than.
const PRESET_GOAL: f64 = 1.2;

/// The study's Lyapunov preset (`twv lyap --model vehicle8 --preset paper --x0
/// 0.1,0,0,0,0,0,0,0`), through the library as the command line runs it.
struct Preset {
    model: ResolvedModel,
    settings: SpectrumSettings,
}

impl Preset {
    fn new() -> Result<Self, String> {
        Ok(Self {
            model: ModelSpec::shipped("vehicle8")
                .resolve()
                .map_err(|e| e.to_string())?,
            settings: SpectrumSettings {
                x0: vec![0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                lyapunov: LyapunovSettings::preset_paper(),
                ..SpectrumSettings::default()
            },
        })
    }

    /// One run: the exponents.
    fn run(&self) -> Result<Vec<f64>, String> {
        spectrum(&self.model, &self.settings, &Silent)
            .map(|r| r.result.exponents)
            .map_err(|e| e.to_string())
    }
}

/// Runs `body` with each build of the kernels this CPU can run in force, best first (naming
/// those it cannot), and leaves the best one in force.
fn each_build(mut body: impl FnMut(twv_kernels::isa::Isa)) {
    use twv_kernels::isa::{available, force, Isa};
    for isa in [Isa::Avx512, Isa::Avx2, Isa::Neon, Isa::Baseline] {
        if !available(isa) {
            println!("  {}: not run (this CPU lacks it)", isa.name());
            continue;
        }
        force(isa);
        body(isa);
    }
    force(Isa::Avx512);
}
