//! The IR's Jacobians against its own f: ∂f/∂x and ∂f/∂u by central differences at a few
//! seeded states, at load. An IR whose `jac_x` was edited by hand (or exported from another
//! version of f) is refused, naming the entry, instead of giving wrong exponents quietly.

use crate::error::Problem;
use crate::types::{Function, Ir};

/// States tried (seeded, the same every time).
const SAMPLES: usize = 4;

/// A deterministic value in [−1, 1] (SplitMix64 of `seed`): no randomness dependency, and
/// every load checks the same points.
fn unit(seed: u64) -> f64 {
    let mut z = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

/// Evaluates output `name` of `f` densely (rows × cols, row-major); `None` if not finite.
fn dense(
    f: &Function,
    name: &str,
    x: &[f64],
    u: &[f64],
    p: &[f64],
    work: &mut [f64],
) -> Option<Vec<f64>> {
    let o = f.output(name)?;
    f.eval(x, u, p, work).ok()?;
    let mut out = vec![0.0; o.rows * o.cols];
    for (r, c, v) in o.entries() {
        out[r * o.cols + c] = work[v];
    }
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// Checks `jac_x` and `jac_u` against central differences of `f` at the IR's defaults.
pub fn check_jacobians(ir: &Ir) -> Result<(), Problem> {
    let (Some(f), nx, nu) = (ir.function("f"), ir.nx(), ir.nu()) else {
        return Ok(());
    };
    let p = ir.defaults();
    let n_work = ir
        .functions()
        .values()
        .map(Function::n_values)
        .max()
        .unwrap_or(0);
    let mut work = vec![0.0; n_work];
    for s in 0..SAMPLES as u64 {
        let x: Vec<f64> = (0..nx as u64).map(|i| unit(s * 1000 + i)).collect();
        let u: Vec<f64> = (0..nu as u64)
            .map(|i| 10.0 * unit(s * 1000 + 500 + i))
            .collect();
        for (jac_name, wrt, n) in [("jac_x", 0usize, nx), ("jac_u", 1usize, nu)] {
            let Some(jf) = ir.function(jac_name) else {
                continue;
            };
            let Some(jac) = dense(jf, jac_name, &x, &u, &p, &mut work) else {
                continue;
            };
            let scale = jac.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
            for c in 0..n {
                let (mut xp, mut xm, mut up, mut um) = (x.clone(), x.clone(), u.clone(), u.clone());
                let base = if wrt == 0 { x[c] } else { u[c] };
                let h = 1e-6 * base.abs().max(1.0);
                if wrt == 0 {
                    xp[c] += h;
                    xm[c] -= h;
                } else {
                    up[c] += h;
                    um[c] -= h;
                }
                let (Some(fp), Some(fm)) = (
                    dense(f, "f", &xp, &up, &p, &mut work),
                    dense(f, "f", &xm, &um, &p, &mut work),
                ) else {
                    continue;
                };
                for r in 0..nx {
                    let fd = (fp[r] - fm[r]) / (2.0 * h);
                    let given = jac[r * n + c];
                    // Central differences are good to ~1e-9 of the scale here; a wrong
                    // entry is off by its own size.
                    if (fd - given).abs() > 1e-5 * (scale + fd.abs()) {
                        let names = |i: usize, of_input: bool| {
                            let list = if of_input { ir.inputs() } else { ir.states() };
                            list.get(i).map_or(i.to_string(), |s| s.name.clone())
                        };
                        return Err(Problem::Function {
                            function: jac_name.to_string(),
                            message: format!(
                                "entry [{}, {}] = {given:e} disagrees with the derivative of f \
                                 ({fd:e} by central differences) at x = {x:?}, u = {u:?}: the \
                                 Jacobian is not that of this f (regenerate the IR)",
                                names(r, false),
                                names(c, wrt == 1)
                            ),
                        });
                    }
                }
            }
        }
    }
    Ok(())
}
