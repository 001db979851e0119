//! Eigenvalues of a real matrix and the naming of its modes: which states take part in each
//! eigenvalue, and which eigenvalues are *drift* (zero eigenvalues of the invariances: position
//! x, y and yaw θ, and in open loop the speeds v_x, v_y, w_z that nothing restores).

use nalgebra::{Complex, DMatrix, Schur, SVD};

use super::error::{check_finite, LinearError};

/// What kind of mode an eigenvalue is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ModeKind {
    /// A zero eigenvalue: the state drifts (integrates) without being restored.
    Drift,
    /// Re λ < 0.
    Stable,
    /// Re λ > 0.
    Unstable,
    /// Re λ = 0, Im λ ≠ 0: an undamped oscillation (e.g. the hanging pendulum).
    Marginal,
}

/// One eigenvalue and the states that take part in it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Mode {
    /// The eigenvalue.
    pub eigenvalue: Complex<f64>,
    /// Its kind.
    pub kind: ModeKind,
    /// States with a participation ≥ 5 % of the largest in the (generalised) eigenspace of this
    /// eigenvalue, largest first.
    pub states: Vec<String>,
}

/// Tolerance below which an eigenvalue counts as zero (or a real part as zero). Repeated zero
/// eigenvalues in Jordan blocks (x with v_x) come out of the QR iteration perturbed by about
/// √ε‖A‖, so the tolerance must be well above that.
pub fn zero_tolerance(a: &DMatrix<f64>) -> f64 {
    1e-6 * a.norm().max(1.0)
}

/// Eigenvalues of a real square matrix, sorted by decreasing real part (then imaginary part).
pub fn eigenvalues(a: &DMatrix<f64>) -> Result<Vec<Complex<f64>>, LinearError> {
    if a.nrows() != a.ncols() {
        return Err(LinearError::Dimension {
            what: "square matrix",
            expected: a.nrows(),
            got: a.ncols(),
        });
    }
    if a.nrows() == 0 {
        return Ok(Vec::new());
    }
    check_finite("matrix", a.iter())?;
    // A bounded iteration count: `Schur::new` would loop forever on pathological input.
    let (schur, shift) = Schur::try_new(a.clone(), f64::EPSILON, 10_000)
        .map(|s| (s, 0.0))
        .or_else(|| {
            // nalgebra deflates where a subdiagonal entry is small against its two diagonal
            // neighbours, which a nilpotent block drives to zero together with it (the bicycle
            // at rest: x and ψ fed by w_R, nothing restoring them), so such a block never
            // deflates. Shifted by ‖A‖ no diagonal is small; every eigenvalue moves by exactly
            // the shift and keeps the ε‖A‖ absolute accuracy of the unshifted iteration.
            let shift = a.norm().max(1.0);
            let shifted = a + DMatrix::identity(a.nrows(), a.ncols()) * shift;
            Schur::try_new(shifted, f64::EPSILON, 10_000).map(|s| (s, shift))
        })
        .ok_or(LinearError::Eigen)?;
    let mut eig: Vec<Complex<f64>> = schur
        .complex_eigenvalues()
        .iter()
        .map(|e| e - shift)
        .collect();
    eig.sort_by(|x, y| y.re.total_cmp(&x.re).then(y.im.total_cmp(&x.im)));
    Ok(eig)
}

/// Largest real part (−∞ for an empty spectrum): the decay rate of the slowest mode.
pub fn spectral_abscissa(eig: &[Complex<f64>]) -> f64 {
    eig.iter().fold(f64::NEG_INFINITY, |m, e| m.max(e.re))
}

/// Classifies an eigenvalue with tolerance `tol`.
pub fn kind_of(e: Complex<f64>, tol: f64) -> ModeKind {
    if e.norm() <= tol {
        ModeKind::Drift
    } else if e.re > tol {
        ModeKind::Unstable
    } else if e.re < -tol {
        ModeKind::Stable
    } else {
        ModeKind::Marginal
    }
}

/// The modes of `a` (n × n) with the states that take part in each. Eigenvalues that agree to
/// the zero tolerance are grouped, and a group of multiplicity m is named from the kernel of
/// (A − μI)^m — the generalised eigenspace — so a Jordan chain such as x ← v_x is named as a
/// whole (the plain eigenvector would name x only).
pub fn modes(a: &DMatrix<f64>, names: &[String]) -> Result<Vec<Mode>, LinearError> {
    let n = a.nrows();
    if names.len() != n {
        return Err(LinearError::Dimension {
            what: "state names",
            expected: n,
            got: names.len(),
        });
    }
    let eig = eigenvalues(a)?;
    let tol = zero_tolerance(a);
    let mut out = Vec::with_capacity(n);
    let mut done = vec![false; n];
    for i in 0..n {
        if done[i] {
            continue;
        }
        let group: Vec<usize> = (i..n)
            .filter(|&j| !done[j] && (eig[j] - eig[i]).norm() <= tol.max(1e-6 * eig[i].norm()))
            .collect();
        let m = group.len();
        let mu = group.iter().map(|&j| eig[j]).sum::<Complex<f64>>() / m as f64;
        let states = participating_states(a, mu, m, names);
        for &j in &group {
            done[j] = true;
            out.push(Mode {
                eigenvalue: eig[j],
                kind: kind_of(eig[j], tol),
                states: states.clone(),
            });
        }
    }
    Ok(out)
}

/// States ranked by their weight in ker (A − μI)^m.
fn participating_states(
    a: &DMatrix<f64>,
    mu: Complex<f64>,
    m: usize,
    names: &[String],
) -> Vec<String> {
    let n = a.nrows();
    let shifted = DMatrix::from_fn(n, n, |i, j| {
        Complex::new(a[(i, j)], 0.0) - if i == j { mu } else { Complex::new(0.0, 0.0) }
    });
    let mut power = shifted.clone();
    for _ in 1..m {
        power = &power * &shifted;
    }
    let svd = SVD::new(power, false, true);
    let Some(v_t) = svd.v_t else {
        return Vec::new();
    };
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&x, &y| svd.singular_values[x].total_cmp(&svd.singular_values[y]));
    // Rows of Vᴴ for the m smallest singular values span the kernel.
    let weight: Vec<f64> = (0..n)
        .map(|s| {
            order[..m.min(order.len())]
                .iter()
                .map(|&k| v_t[(k, s)].norm_sqr())
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let top = weight.iter().fold(0.0_f64, |x, &w| x.max(w));
    let mut ranked: Vec<usize> = (0..n)
        .filter(|&s| weight[s] >= 0.05 * top && top > 0.0)
        .collect();
    ranked.sort_by(|&x, &y| weight[y].total_cmp(&weight[x]));
    ranked.into_iter().map(|s| names[s].clone()).collect()
}
