//! Physical checks on a mechanical model (docs/src/conventions.md): facts any correct model satisfies,
//! computed on the model under audit without looking at the hand model.

use nalgebra::DMatrix;
use serde::Serialize;
use twv_model::Mechanical;

use super::sampling::Sample;
use crate::hand_model::VehicleParams;

/// Outcome of one physical check.
#[derive(Debug, Clone, Serialize)]
pub struct PhysicsCheck {
    pub name: &'static str,
    /// The measured error (relative unless the name says otherwise).
    pub error: f64,
    pub tolerance: f64,
    pub passed: bool,
    /// What was compared, for a person reading the table.
    pub detail: String,
}

impl PhysicsCheck {
    pub fn new(name: &'static str, error: f64, tolerance: f64, detail: String) -> Self {
        // NaN must fail: compare the negation.
        let passed = error <= tolerance;
        Self {
            name,
            error,
            tolerance,
            passed,
            detail,
        }
    }
}

/// λ² = m_p g l M_x / (I_p M_x − m_p² l²) of the upright: positive for a pendulum above its
/// hinge (l > 0: eigenvalues ±λ), negative below it (l < 0: ±i√−λ²).
pub fn upright_lambda_squared(p: &VehicleParams, rolling_wheels: bool) -> f64 {
    let mx = if rolling_wheels {
        p.m2 + 2.0 * p.m_w + 2.0 * p.j_a / (p.r * p.r)
    } else {
        p.m1 + p.m2
    };
    let ip = p.i2[1] + p.m2 * p.b * p.b;
    p.m2 * p.g * p.b * mx / (ip * mx - p.m2 * p.m2 * p.b * p.b)
}

fn eigenvalues<const NX: usize>(jac: &[[f64; NX]; NX]) -> Vec<(f64, f64)> {
    // Dynamic size: nalgebra's eigen-solvers need dimension bounds a const generic cannot give.
    let a = DMatrix::<f64>::from_fn(NX, NX, |i, j| jac[i][j]);
    a.complex_eigenvalues()
        .iter()
        .map(|c| (c.re, c.im))
        .collect()
}

/// How far the non-zero eigenvalue pair of `eig` is from ±√s (s ≥ 0: real) or ±i√−s (s < 0:
/// imaginary), relative to √|s| (at least 1e-3 /s), with what was found.
fn pair_error(eig: &[(f64, f64)], s: f64) -> (f64, String) {
    let mu = s.abs().sqrt();
    let scale = mu.max(1e-3);
    let max_re = eig.iter().fold(f64::NEG_INFINITY, |m, e| m.max(e.0));
    let min_re = eig.iter().fold(f64::INFINITY, |m, e| m.min(e.0));
    let max_im = eig.iter().fold(f64::NEG_INFINITY, |m, e| m.max(e.1));
    let max_abs_re = eig.iter().fold(0.0_f64, |m, e| m.max(e.0.abs()));
    if s >= 0.0 {
        let err = (max_re - mu).abs().max((min_re + mu).abs()) / scale;
        (
            err,
            format!("expected ±{mu:.12}; largest real part {max_re:.12}, smallest {min_re:.12}"),
        )
    } else {
        let err = ((max_im - mu).abs() + max_abs_re) / scale;
        (
            err,
            format!("expected ±{mu:.12}i; largest imaginary part {max_im:.12}, largest |real| {max_abs_re:.1e}"),
        )
    }
}

/// The rest states' eigenvalues against λ² (see [`upright_lambda_squared`]): upright ±√λ²,
/// hanging (Φ = π) ±√−λ², with zeros besides (real for the sign that is positive, imaginary
/// for the other).
pub fn equilibrium_eigenvalues<const NX: usize, const NU: usize, const NS: usize, M>(
    model: &M,
    lambda_squared: f64,
) -> [PhysicsCheck; 2]
where
    M: Mechanical<NX, NU, NS>,
{
    let mut jac = [[0.0; NX]; NX];
    model.jac_x(&[0.0; NX], &[0.0; NU], &mut jac);
    let (up_err, up_detail) = pair_error(&eigenvalues(&jac), lambda_squared);
    let mut hanging = [0.0; NX];
    hanging[0] = std::f64::consts::PI;
    model.jac_x(&hanging, &[0.0; NU], &mut jac);
    let (down_err, down_detail) = pair_error(&eigenvalues(&jac), -lambda_squared);
    [
        PhysicsCheck::new(
            "upright eigenvalues ±√λ²",
            up_err,
            1e-9,
            format!("λ² = {lambda_squared:.12} 1/s²; {up_detail}"),
        ),
        PhysicsCheck::new("hanging eigenvalues ±√−λ²", down_err, 1e-9, down_detail),
    ]
}

fn relative(a: f64, b: f64, scale: f64) -> f64 {
    (a - b).abs() / scale.max(f64::MIN_POSITIVE)
}

/// q̇ of the state derivative (the coordinate rows of f).
fn coordinate_rates<const NX: usize, const NU: usize, const NS: usize, M>(
    model: &M,
    s: &Sample<NX, NU>,
) -> [f64; NX]
where
    M: Mechanical<NX, NU, NS>,
{
    let mut f = [0.0; NX];
    model.f(&s.x, &s.u, &mut f);
    for v in f.iter_mut().skip(NX - NS) {
        *v = 0.0;
    }
    f
}

/// pᵀ C(q,p) p = ½ pᵀ Ṁ p: the velocity terms do no work (Ṁ by central differences along q̇).
pub fn gyroscopic_no_work<const NX: usize, const NU: usize, const NS: usize, M>(
    model: &M,
    samples: &[Sample<NX, NU>],
) -> PhysicsCheck
where
    M: Mechanical<NX, NU, NS>,
{
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    for s in samples {
        let qdot = coordinate_rates(model, s);
        let p = &s.x[NX - NS..];
        let (mut xp, mut xm) = (s.x, s.x);
        for i in 0..NX {
            xp[i] += h * qdot[i];
            xm[i] -= h * qdot[i];
        }
        let (mut mp, mut mm) = ([[0.0; NS]; NS], [[0.0; NS]; NS]);
        model.mass_matrix(&xp, &mut mp);
        model.mass_matrix(&xm, &mut mm);
        let mut cp = [0.0; NS];
        model.cp(&s.x, &mut cp);
        let (mut half, mut pcp, mut scale) = (0.0, 0.0, 0.0);
        for i in 0..NS {
            pcp += p[i] * cp[i];
            scale += (p[i] * cp[i]).abs();
            for j in 0..NS {
                half += 0.5 * p[i] * (mp[i][j] - mm[i][j]) / (2.0 * h) * p[j];
            }
        }
        worst = worst.max(relative(pcp, half, scale.max(1.0)));
    }
    PhysicsCheck::new(
        "pᵀCp = ½ pᵀṀp",
        worst,
        1e-7,
        "Ṁ by central differences (h = 1e-6) along q̇".into(),
    )
}

/// dE/dt = Qᵀp pointwise (energy balance), dE/dt by central differences along f.
pub fn energy_balance<const NX: usize, const NU: usize, const NS: usize, M>(
    model: &M,
    samples: &[Sample<NX, NU>],
) -> PhysicsCheck
where
    M: Mechanical<NX, NU, NS>,
{
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    for s in samples {
        let mut f = [0.0; NX];
        model.f(&s.x, &s.u, &mut f);
        let (mut xp, mut xm) = (s.x, s.x);
        for i in 0..NX {
            xp[i] += h * f[i];
            xm[i] -= h * f[i];
        }
        let (ep, em) = (model.energy(&xp), model.energy(&xm));
        let rate = (ep - em) / (2.0 * h);
        // The difference quotient's own round-off, ~ε|E|/h, grows with the energy (a 100 t
        // base): allowed for at 100 ε|E|/h beside the 1e-6 relative tolerance.
        let round_off = 1e8 * f64::EPSILON * ep.abs().max(em.abs()) / h;
        let mut q = [0.0; NS];
        model.input_forces(&s.x, &s.u, &mut q);
        let power: f64 = q.iter().zip(&s.x[NX - NS..]).map(|(a, b)| a * b).sum();
        let scale: f64 = q
            .iter()
            .zip(&s.x[NX - NS..])
            .map(|(a, b)| (a * b).abs())
            .sum();
        worst = worst.max(relative(rate, power, scale.max(1.0) + round_off));
    }
    PhysicsCheck::new(
        "dE/dt = Qᵀp",
        worst,
        1e-6,
        "energy rate by central differences (h = 1e-6) along ẋ".into(),
    )
}

/// The base centroid height `a` does not enter f: models built with two values of `a` agree bit
/// for bit.
pub fn height_independence<const NX: usize, const NU: usize, const NS: usize, M>(
    with_a: impl Fn(f64) -> M,
    samples: &[Sample<NX, NU>],
) -> PhysicsCheck
where
    M: Mechanical<NX, NU, NS>,
{
    let (low, high) = (with_a(0.1), with_a(7.0));
    let mut worst: f64 = 0.0;
    for s in samples {
        let (mut f1, mut f2) = ([0.0; NX], [0.0; NX]);
        low.f(&s.x, &s.u, &mut f1);
        high.f(&s.x, &s.u, &mut f2);
        for (a, b) in f1.iter().zip(&f2) {
            worst = worst.max(relative(*a, *b, b.abs().max(1.0)));
        }
    }
    PhysicsCheck::new(
        "a does not enter f",
        worst,
        0.0,
        "f with a = 0.1 m vs a = 7 m".into(),
    )
}

/// Indices of the lateral states (y, θ, v_y, w_z) that mirror symmetry flips.
fn lateral(states: &[&str]) -> Vec<usize> {
    states
        .iter()
        .enumerate()
        .filter(|(_, n)| matches!(**n, "y" | "theta" | "v_y" | "w_z"))
        .map(|(i, _)| i)
        .collect()
}

/// The mirror image of an input: T2 → −T2, or the wheel torques swapped.
fn mirror_input<const NU: usize>(inputs: &[&str], u: &[f64; NU]) -> [f64; NU] {
    let mut out = *u;
    if inputs.contains(&"tau_L") {
        out.reverse();
    } else if let Some(i) = inputs.iter().position(|n| *n == "T2") {
        out[i] = -out[i];
    }
    out
}

/// Mirror symmetry: (y, θ, v_y, w_z, T2) → −(…) maps solutions to solutions; and with T2 = 0
/// (equal wheel torques) and no lateral motion the motion stays planar.
pub fn symmetry<const NX: usize, const NU: usize, const NS: usize, M>(
    model: &M,
    samples: &[Sample<NX, NU>],
) -> [PhysicsCheck; 2]
where
    M: Mechanical<NX, NU, NS>,
{
    let info = model.info();
    let lat = lateral(info.states);
    let (mut mirror_err, mut planar_err): (f64, f64) = (0.0, 0.0);
    for s in samples {
        let (mut f, mut fm) = ([0.0; NX], [0.0; NX]);
        model.f(&s.x, &s.u, &mut f);
        let mut xm = s.x;
        lat.iter().for_each(|&i| xm[i] = -xm[i]);
        model.f(&xm, &mirror_input(info.inputs, &s.u), &mut fm);
        let scale = f.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        for i in 0..NX {
            let expected = if lat.contains(&i) { -f[i] } else { f[i] };
            mirror_err = mirror_err.max(relative(fm[i], expected, scale));
        }
        let mut xp = s.x;
        lat.iter().for_each(|&i| xp[i] = 0.0);
        let mirrored = mirror_input(info.inputs, &s.u);
        let mut up = s.u;
        for (a, b) in up.iter_mut().zip(mirrored) {
            *a = 0.5 * (*a + b);
        }
        model.f(&xp, &up, &mut f);
        for &i in &lat {
            planar_err = planar_err.max(f[i].abs());
        }
    }
    [
        PhysicsCheck::new(
            "mirror symmetry",
            mirror_err,
            1e-13,
            "f(Sx, Su) = S f(x, u)".into(),
        ),
        PhysicsCheck::new(
            "planar motion stays planar (abs)",
            planar_err,
            0.0,
            "lateral rates at planar states with symmetric input".into(),
        ),
    ]
}
