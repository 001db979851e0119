//! The Whipple bicycle's CasADi C (feature `bicycle-peer`; build.rs writes it with `export-c
//! --model whipple --tangents 9 --runtime-only` and compiles it at -O3): the peer of the
//! bicycle's JIT in `cargo bench -p twv-bench --bench jit`, the bicycle having no generated
//! Rust kernels. Checked against the JIT before anything is timed, as [`crate::gate`] checks
//! vehicle8's C against its Rust.

use twv_ir::{Interpreted, Ir};
use twv_model::Model;

use std::ffi::c_int;

use crate::{
    check_within, jw_scale, no_mismatches, output_magnitudes, uniform, CFunction, CasadiInt, Entry,
};

/// The bicycle's states, inputs, and the tangent vectors of its J·W (one per state).
pub const NX: usize = 9;
pub const NU: usize = 2;
pub const K: usize = NX;

casadi_function!(W_F = "whipple_f");
casadi_function!(W_F_JAC_X = "whipple_f_jac_x");
casadi_function!(W_F_JW9 = "whipple_f_jw9");

/// CasADi's C for the bicycle with runtime parameters.
pub struct BicycleC {
    params: Vec<f64>,
    nnz: usize,
    f: CFunction,
    f_jac_x: CFunction,
    f_jw: CFunction,
}

impl BicycleC {
    /// The C functions with `model`'s parameter values, checked against its sizes and its
    /// ∂f/∂x pattern.
    pub fn new(model: &Interpreted<NX, NU>) -> Result<Self, String> {
        let params = model.params().to_vec();
        let inputs = [(NX, 1), (NU, 1), (params.len(), 1)];
        let jw_inputs = [(NX, 1), (NU, 1), (params.len(), 1), (NX, K)];
        let jac = Err((model.jac_x_colind(), model.jac_x_row()));
        Ok(Self {
            nnz: model.jac_x_row().len(),
            f: CFunction::checked(W_F, &inputs, &[Ok((NX, 1))])?,
            f_jac_x: CFunction::checked(W_F_JAC_X, &inputs, &[Ok((NX, 1)), jac])?,
            f_jw: CFunction::checked(W_F_JW9, &jw_inputs, &[Ok((NX, 1)), Ok((NX, K))])?,
            params,
        })
    }

    /// ẋ = f(x, u).
    #[inline(always)]
    pub fn f(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [f64; NX]) {
        let args = [x.as_ptr(), u.as_ptr(), self.params.as_ptr()];
        // SAFETY: sizes checked in `new`.
        unsafe { self.f.call(args, [out.as_mut_ptr()]) }
    }

    /// ẋ and the stored entries of ∂f/∂x (the IR's CCS order) into `jac`, which must hold
    /// exactly that many.
    #[inline(always)]
    pub fn f_jac_x(&self, x: &[f64; NX], u: &[f64; NU], f: &mut [f64; NX], jac: &mut [f64]) {
        assert_eq!(
            jac.len(),
            self.nnz,
            "the bicycle's ∂f/∂x has {} entries",
            self.nnz
        );
        let args = [x.as_ptr(), u.as_ptr(), self.params.as_ptr()];
        // SAFETY: sizes checked in `new` and above.
        unsafe { self.f_jac_x.call(args, [f.as_mut_ptr(), jac.as_mut_ptr()]) }
    }

    /// ẋ and `out[k] = (∂f/∂x) w[k]`.
    #[inline(always)]
    pub fn f_jw(
        &self,
        x: &[f64; NX],
        u: &[f64; NU],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        out: &mut [[f64; NX]; K],
    ) {
        let w = w.as_ptr().cast::<f64>();
        let args = [x.as_ptr(), u.as_ptr(), self.params.as_ptr(), w];
        // SAFETY: sizes checked in `new`; `[[f64; NX]; K]` is NX·K contiguous doubles.
        unsafe {
            self.f_jw
                .call(args, [f.as_mut_ptr(), out.as_mut_ptr().cast::<f64>()])
        }
    }
}

/// A state of the bicycle rolling near upright at ~4 m/s (the benchmark bicycle's rear wheel
/// radius is 0.3 m; the IR's `steady` state at 1 m/s has w_R = 1/0.3 and every angle 0): lean,
/// steer and their rates within ±0.3, the pitch within ±0.02, the heading and position anywhere;
/// inputs (the lean and steer torques) within ±5 N·m; W in [-1, 1]. `seed` 0 is the point the
/// benchmark times.
pub fn point(seed: u64) -> ([f64; NX], [f64; NU], [[f64; NX]; K]) {
    let mut next = uniform(seed + 1);
    // psi, x, y, phi, theta, delta, w_phi, w_R, w_delta (the IR's order, checked by the gate).
    let centre = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 4.0 / 0.3, 0.0];
    let spread = [3.0, 10.0, 10.0, 0.3, 0.02, 0.3, 0.3, 1.0, 0.3];
    let x = std::array::from_fn(|i| centre[i] + spread[i] * next());
    let u = std::array::from_fn(|_| 5.0 * next());
    let w = std::array::from_fn(|_| std::array::from_fn(|_| next()));
    (x, u, w)
}

/// Checks at the benchmark's point and `n_random` more that the JIT and the C agree within
/// 1e-13 of the size of the terms behind each entry (`magnitude`; for J·W, Σ_c |J_rc| |w_kc|):
/// f, ∂f/∂x and f + J·W.
pub fn gate(ir: &Ir, jit: &Interpreted<NX, NU>, c: &BicycleC, n_random: u64) -> Result<(), String> {
    let states: Vec<&str> = ir.states().iter().map(|s| s.name.as_str()).collect();
    let expected = [
        "psi", "x", "y", "phi", "theta", "delta", "w_phi", "w_R", "w_delta",
    ];
    if states != expected {
        return Err(format!(
            "the bicycle's states are {states:?}, the bench expects {expected:?}"
        ));
    }
    let mut errors = Vec::new();
    for seed in 0..=n_random {
        let (x, u, w) = point(seed);
        let at = format!("point {seed}");
        let mut check = |what: &str, jit: &[f64], c: &[f64], scale: &[f64]| {
            check_within(&mut errors, &at, what, jit, c, scale)
        };
        let scale = |function: &str, output: &str| {
            output_magnitudes(ir, function, output, (&x, &u, jit.params()))
        };
        let (f_scale, jac_scale) = (scale("f", "f")?, scale("f_jac_x", "jac_x")?);

        let (mut fj, mut fc) = ([0.0; NX], [0.0; NX]);
        jit.f(&x, &u, &mut fj);
        c.f(&x, &u, &mut fc);
        check("f", &fj, &fc, &f_scale);

        let (mut jj, mut jc) = (vec![0.0; c.nnz], vec![0.0; c.nnz]);
        jit.jac_x_sparse(&x, &u, &mut jj);
        c.f_jac_x(&x, &u, &mut fc, &mut jc);
        check("f_jac_x f", &fj, &fc, &f_scale);
        check("jac_x", &jj, &jc, &jac_scale);

        let pattern = (jit.jac_x_colind(), jit.jac_x_row());
        let jw_scale = jw_scale(&jac_scale, pattern, &w);
        let (mut jwj, mut jwc) = ([[0.0; NX]; K], [[0.0; NX]; K]);
        jit.f_jw::<K>(&x, &u, &w, &mut fj, &mut jwj);
        c.f_jw(&x, &u, &w, &mut fc, &mut jwc);
        check("f_jw f", &fj, &fc, &f_scale);
        check(
            "J·W",
            jwj.as_flattened(),
            jwc.as_flattened(),
            jw_scale.as_flattened(),
        );
    }
    no_mismatches(errors, "the bicycle's JIT (twv) and CasADi's C")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn whipple() -> (Ir, Interpreted<NX, NU>) {
        let text = twv_generated::shipped_ir_json("whipple").expect("the bicycle is shipped");
        let ir = twv_ir::parse_ir(text, "generated/ir/whipple.json").expect("its IR is valid");
        let model = Interpreted::with_defaults(&ir).expect("its defaults are valid");
        (ir, model)
    }

    #[test]
    fn the_bicycles_c_agrees_with_its_ir_and_the_gate_catches_a_changed_parameter() {
        let (ir, model) = whipple();
        let c = BicycleC::new(&model).unwrap();
        gate(&ir, &model, &c, 4).unwrap();
        // One parameter off by one part in 10⁹ on the C side: the gate must see it.
        let mut params = model.params().to_vec();
        params[0] *= 1.0 + 1e-9;
        let off = BicycleC::new(&model.with_params(&params).unwrap()).unwrap();
        let err = gate(&ir, &model, &off, 4).unwrap_err();
        assert!(err.contains("mismatches"), "{err}");
    }
}
