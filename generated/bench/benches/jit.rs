//! `cargo bench -p twv-bench --bench jit`: a model IR at run time — compiled by the JIT
//! (`twv-jit`) or interpreted — against the generated code built into twv, side by side in one
//! run: the time to prepare each model, f + J·W per call, and RK4 integrations.
//!
//! Without `--bench` (`cargo test --benches`) it only checks that the JIT has the interpreter's
//! bits on every model it times, and stops. A benchmark, not a test: it asserts no time.

use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

use twv_bench::{compare, time, Plan};
use twv_generated::{HenonHeiles, Lorenz, Vehicle8};
use twv_ir::{Interpreted, Ir};
use twv_model::Model;

/// The shipped IR of `name`.
fn shipped(name: &str) -> Ir {
    let text = twv_generated::shipped_ir_json(name).unwrap_or_else(|| panic!("{name} is shipped"));
    twv_ir::parse_ir(text, &format!("generated/ir/{name}.json")).expect("shipped IR is valid")
}

/// The JIT-compiled model of `ir` (its defaults), and the seconds until it is ready for a
/// Lyapunov run: the native code made, and `f` and `f_jac_x` compiled by a first call of each.
fn jit<const NX: usize, const NU: usize>(ir: &Ir) -> Result<(Interpreted<NX, NU>, f64), String> {
    let start = Instant::now();
    let code = twv_jit::compile(ir).map_err(|e| e.to_string())?;
    let model =
        Interpreted::with_native(ir, &ir.defaults(), Some(code)).map_err(|e| e.to_string())?;
    let (x, u, w) = point::<NX, NU, 1>();
    let (mut f, mut out) = ([0.0; NX], [[0.0; NX]; 1]);
    model.f(&x, &u, &mut f);
    model.f_jw(&x, &u, &w, &mut f, &mut out);
    Ok((model, start.elapsed().as_secs_f64()))
}

/// A deterministic state, inputs and K tangent vectors with every entry non-trivial.
fn point<const NX: usize, const NU: usize, const K: usize>(
) -> ([f64; NX], [f64; NU], [[f64; NX]; K]) {
    let x = std::array::from_fn(|i| 0.3 + 0.17 * i as f64);
    let u = std::array::from_fn(|i| 1.5 - 0.5 * i as f64);
    let w = std::array::from_fn(|k| std::array::from_fn(|i| ((k * NX + i) as f64 * 0.37).sin()));
    (x, u, w)
}

/// f + J·W of `a` and `b` at the point, bit for bit, or the first difference.
fn same_bits<const NX: usize, const NU: usize, const K: usize>(
    a: &impl Model<NX, NU>,
    b: &impl Model<NX, NU>,
    what: &str,
) -> Result<(), String> {
    let (x, u, w) = point::<NX, NU, K>();
    let (mut fa, mut ja, mut fb, mut jb) = ([0.0; NX], [[0.0; NX]; K], [0.0; NX], [[0.0; NX]; K]);
    a.f_jw::<K>(&x, &u, &w, &mut fa, &mut ja);
    b.f_jw::<K>(&x, &u, &w, &mut fb, &mut jb);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    if bits(&fa) != bits(&fb) || bits(ja.as_flattened()) != bits(jb.as_flattened()) {
        return Err(format!(
            "{what}: the JIT and the interpreter differ: f {fa:?} vs {fb:?}"
        ));
    }
    Ok(())
}

/// One row of the per-call table: f + J·W with K tangent vectors, built-in generated code (if
/// any) against the JIT (paired samples) and the interpreter.
fn per_call<const NX: usize, const NU: usize, const K: usize>(
    plan: Plan,
    name: &str,
    generated: Option<&impl Model<NX, NU>>,
    jitted: &impl Model<NX, NU>,
    interpreted: &impl Model<NX, NU>,
) {
    let (x, u, w) = point::<NX, NU, K>();
    fn call<const NX: usize, const NU: usize, const K: usize>(
        m: &impl Model<NX, NU>,
        (x, u, w): (&[f64; NX], &[f64; NU], &[[f64; NX]; K]),
    ) {
        let (mut f, mut out) = ([0.0; NX], [[0.0; NX]; K]);
        black_box(m).f_jw::<K>(black_box(x), black_box(u), black_box(w), &mut f, &mut out);
        black_box((&mut f, &mut out));
    }
    let at = (&x, &u, &w);
    let interp = time(plan, || call(interpreted, at));
    match generated {
        Some(g) => {
            let pair = compare(plan, || call(jitted, at), || call(g, at));
            println!(
                "| {name} | {K} | {} | {} | {} | **{:.2}** | {:.1} |",
                pair.c,
                pair.twv,
                interp,
                pair.ratio.median,
                interp.median / pair.c.median
            );
        }
        None => {
            let j = time(plan, || call(jitted, at));
            println!(
                "| {name} | {K} | — | {j} | {interp} | — | {:.1} (interpreter/JIT) |",
                interp.median / j.median
            );
        }
    }
}

/// Seconds for `steps` RK4 steps of ẋ = f(x, 0) from `x0` with step `h`: the integration every
/// twv job runs, here through the model's `f` alone.
fn rk4<const NX: usize, const NU: usize>(
    m: &impl Model<NX, NU>,
    x0: [f64; NX],
    h: f64,
    steps: usize,
) -> (f64, [f64; NX]) {
    let u = [0.0; NU];
    let f = |x: &[f64; NX]| {
        let mut d = [0.0; NX];
        m.f(x, &u, &mut d);
        d
    };
    let add = |x: &[f64; NX], k: &[f64; NX], s: f64| std::array::from_fn(|i| x[i] + s * k[i]);
    let start = Instant::now();
    let mut x = x0;
    for _ in 0..steps {
        let k1 = f(&x);
        let k2 = f(&add(&x, &k1, 0.5 * h));
        let k3 = f(&add(&x, &k2, 0.5 * h));
        let k4 = f(&add(&x, &k3, h));
        x = std::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
    }
    (start.elapsed().as_secs_f64(), black_box(x))
}

/// The bicycle's JIT against CasADi's C of the same IR (gcc -O3), paired, per function.
#[cfg(feature = "bicycle-peer")]
fn bicycle_against_c(plan: Plan, jit: &Interpreted<9, 2>, c: &twv_bench::bicycle::BicycleC) {
    use twv_bench::bicycle::{point, K, NX};
    let (x, u, w) = point(0);
    let nnz = jit.jac_x_row().len();
    // Each side writes its own buffers (the closures hold them mutably).
    let (mut fa, mut fb) = ([0.0; NX], [0.0; NX]);
    let (mut ja, mut jb) = (vec![0.0; nnz], vec![0.0; nnz]);
    let (mut wa, mut wb) = ([[0.0; NX]; K], [[0.0; NX]; K]);
    println!(
        "the bicycle (whipple, runtime parameters): its JIT against CasADi's C of the same IR \
         (gcc -O3), ns per call (median ±half the IQR, paired):"
    );
    println!();
    println!("| function | JIT | CasADi C | JIT / C |");
    println!("|---|---:|---:|---:|");
    let row = |what: &str, pair: twv_bench::Pair| {
        println!(
            "| {what} | {} | {} | **{:.2}** |",
            pair.twv, pair.c, pair.ratio.median
        );
    };
    let (x, u, w) = (black_box(&x), black_box(&u), black_box(&w));
    row(
        "f",
        compare(
            plan,
            || black_box(jit).f(x, u, black_box(&mut fa)),
            || c.f(x, u, black_box(&mut fb)),
        ),
    );
    // The JIT's f and ∂f/∂x are two calls (the jobs need f alone or f with J·W); the C's one.
    row(
        "f, ∂f/∂x (stored entries; the JIT in two calls)",
        compare(
            plan,
            || {
                black_box(jit).f(x, u, black_box(&mut fa));
                black_box(jit).jac_x_sparse(x, u, black_box(&mut ja));
            },
            || c.f_jac_x(x, u, black_box(&mut fb), black_box(&mut jb)),
        ),
    );
    row(
        "f + J·W, K = 9",
        compare(
            plan,
            || black_box(jit).f_jw::<K>(x, u, w, black_box(&mut fa), black_box(&mut wa)),
            || c.f_jw(x, u, w, black_box(&mut fb), black_box(&mut wb)),
        ),
    );
    println!();
}

fn main() -> ExitCode {
    let timing = std::env::args().any(|a| a == "--bench");
    match run(timing) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("twv-bench jit: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(timing: bool) -> Result<(), String> {
    let (v8_ir, lz_ir, hh_ir, wh_ir) = (
        shipped("vehicle8"),
        shipped("lorenz"),
        shipped("henon_heiles"),
        shipped("whipple"),
    );
    let (v8_jit, v8_prep) = jit::<8, 2>(&v8_ir)?;
    let (lz_jit, lz_prep) = jit::<3, 0>(&lz_ir)?;
    let (hh_jit, hh_prep) = jit::<4, 0>(&hh_ir)?;
    let (wh_jit, wh_prep) = jit::<9, 2>(&wh_ir)?;
    let interp = |ir: &Ir| ir.defaults();
    let v8_int = Interpreted::<8, 2>::new(&v8_ir, &interp(&v8_ir)).map_err(|e| e.to_string())?;
    let lz_int = Interpreted::<3, 0>::new(&lz_ir, &interp(&lz_ir)).map_err(|e| e.to_string())?;
    let hh_int = Interpreted::<4, 0>::new(&hh_ir, &interp(&hh_ir)).map_err(|e| e.to_string())?;
    let wh_int = Interpreted::<9, 2>::new(&wh_ir, &interp(&wh_ir)).map_err(|e| e.to_string())?;
    same_bits::<8, 2, 8>(&v8_jit, &v8_int, "vehicle8")?;
    same_bits::<3, 0, 3>(&lz_jit, &lz_int, "lorenz")?;
    same_bits::<4, 0, 4>(&hh_jit, &hh_int, "henon_heiles")?;
    same_bits::<9, 2, 9>(&wh_jit, &wh_int, "whipple")?;
    println!(
        "correctness gate passed: the JIT has the interpreter's bits (f + J·W) on all four models"
    );
    #[cfg(feature = "bicycle-peer")]
    let wh_c = {
        use twv_bench::bicycle;
        let c = bicycle::BicycleC::new(&wh_jit)?;
        bicycle::gate(&wh_ir, &wh_jit, &c, 16)?;
        println!(
            "correctness gate passed: the bicycle's JIT and CasADi's C of its IR agree within \
             1e-13 of the terms' size (f, ∂f/∂x, J·W) at 17 states"
        );
        c
    };
    if !timing {
        return Ok(());
    }

    let plan = Plan::from_env()?;
    println!(
        "{}; the JIT targets this CPU (Cranelift, host features)",
        twv_analysis::machine::describe()
    );
    println!();
    println!(
        "preparing a model at run time: from a loaded IR to native f and f + J·W (compiled on \
         first use), one run each:"
    );
    println!();
    println!("| model | instructions of f, f_jac_x | JIT ready, ms |");
    println!("|---|---:|---:|");
    for (ir, seconds) in [
        (&v8_ir, v8_prep),
        (&lz_ir, lz_prep),
        (&hh_ir, hh_prep),
        (&wh_ir, wh_prep),
    ] {
        let n = |name: &str| ir.function(name).map_or(0, |f| f.n_values());
        let (f, fj) = (n("f"), n("f_jac_x"));
        println!("| {} | {f}, {fj} | {:.1} |", ir.model(), seconds * 1e3);
    }
    println!();
    println!(
        "f + J·W per call, ns (median ±half the IQR; built-in and JIT paired, {} samples of >= {} ms):",
        plan.samples,
        plan.sample_time.as_millis()
    );
    println!();
    println!("| model | K | built-in generated | JIT | interpreter | JIT / built-in | interpreter / built-in |");
    println!("|---|---:|---:|---:|---:|---:|---:|");
    let v8 = Vehicle8::with_defaults();
    let (lz, hh) = (Lorenz::with_defaults(), HenonHeiles::with_defaults());
    per_call::<8, 2, 1>(plan, "vehicle8", Some(&v8), &v8_jit, &v8_int);
    per_call::<8, 2, 8>(plan, "vehicle8", Some(&v8), &v8_jit, &v8_int);
    per_call::<3, 0, 3>(plan, "lorenz", Some(&lz), &lz_jit, &lz_int);
    per_call::<4, 0, 4>(plan, "henon_heiles", Some(&hh), &hh_jit, &hh_int);
    per_call::<9, 2, 9>(
        plan,
        "whipple",
        None::<&Interpreted<9, 2>>,
        &wh_jit,
        &wh_int,
    );
    println!();
    #[cfg(feature = "bicycle-peer")]
    bicycle_against_c(plan, &wh_jit, &wh_c);
    #[cfg(not(feature = "bicycle-peer"))]
    println!(
        "(the bicycle against CasADi's C: build with `--features twv-bench/bicycle-peer`, as \
         `.ci/speed-report.sh` does)"
    );
    println!();
    let steps = 2_000_000;
    println!(
        "Lorenz, {steps} RK4 steps (h = 1e-3, from (1, 1, 1)), seconds, fastest of 5 runs each:"
    );
    println!();
    // The fastest of five alternating runs of each: one run is at the mercy of the host.
    let (mut tg, mut tj, mut ti) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let (mut xg, mut xj, mut xi) = ([0.0; 3], [0.0; 3], [0.0; 3]);
    for _ in 0..5 {
        let (t, x) = rk4(&lz, [1.0; 3], 1e-3, steps);
        (tg, xg) = (tg.min(t), x);
        let (t, x) = rk4(&lz_jit, [1.0; 3], 1e-3, steps);
        (tj, xj) = (tj.min(t), x);
        let (t, x) = rk4(&lz_int, [1.0; 3], 1e-3, steps);
        (ti, xi) = (ti.min(t), x);
    }
    println!(
        "| built-in generated | JIT | interpreter | JIT / built-in | interpreter / built-in |"
    );
    println!("|---:|---:|---:|---:|---:|");
    println!(
        "| {tg:.3} | {tj:.3} | {ti:.3} | **{:.2}** | {:.1} |",
        tj / tg,
        ti / tg
    );
    let same = xg == xj && xj == xi;
    println!();
    println!(
        "final states {}",
        if same {
            "bit-identical on all three paths"
        } else {
            "DIFFER"
        }
    );
    if !same {
        return Err(format!("final states differ: {xg:?} {xj:?} {xi:?}"));
    }
    Ok(())
}
