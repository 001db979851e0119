//! The single-input single-output plant y = c x, ẋ = A x + b u, reduced to its minimal
//! (controllable and observable) part by a Kalman decomposition built from orthonormal Krylov
//! bases.
//!
//! Why reduce: a vehicle's A is singular (x, y, θ and the speeds nothing restores give zero
//! eigenvalues), so c (sI − A)⁻¹ b cannot be evaluated at s = 0 from the full matrices even
//! though the transfer from F to Φ is finite there; and the modes the loop cannot see must be
//! reported apart ("uncontrolled drift"), because no pitch gain moves them.

use nalgebra::{Complex, DMatrix, DVector, RowDVector};

use super::error::{check_finite, LinearError};
use super::modes::eigenvalues;

/// Why a part of the state is invisible to the loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum HiddenKind {
    /// The input cannot move it.
    Uncontrollable,
    /// The output does not see it.
    Unobservable,
}

/// A part of the state the loop cannot move or see; its eigenvalues are the same in open and
/// closed loop.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HiddenPart {
    /// Why it is hidden.
    pub kind: HiddenKind,
    /// Its eigenvalues.
    pub eigenvalues: Vec<Complex<f64>>,
    /// The states that span it (weight ≥ 5 % of the largest), largest first.
    pub states: Vec<String>,
}

/// A SISO plant in minimal form, with the hidden parts kept for reporting.
#[derive(Debug, Clone, PartialEq)]
pub struct SisoPlant {
    a: DMatrix<f64>,
    b: DVector<f64>,
    c: RowDVector<f64>,
    hidden: Vec<HiddenPart>,
}

/// Orthonormal basis of the Krylov space span{v, Mv, M²v, …} (the smallest M-invariant
/// subspace containing v), by Arnoldi with re-orthogonalisation.
pub(crate) fn krylov_basis(m: &DMatrix<f64>, v: &DVector<f64>) -> DMatrix<f64> {
    let n = m.nrows();
    let tol = 1e-10 * m.norm().max(1.0);
    let mut basis: Vec<DVector<f64>> = Vec::with_capacity(n);
    let mut w = v.clone();
    let norm = w.norm();
    if norm == 0.0 {
        return DMatrix::zeros(n, 0);
    }
    w /= norm;
    basis.push(w);
    while basis.len() < n {
        let mut next = m * basis.last().expect("basis is not empty");
        for _ in 0..2 {
            for q in &basis {
                let proj = q.dot(&next);
                next -= q * proj;
            }
        }
        let norm = next.norm();
        if norm <= tol {
            break;
        }
        basis.push(next / norm);
    }
    DMatrix::from_columns(&basis)
}

/// Orthonormal basis of the orthogonal complement of the columns of `q` (orthonormal), chosen
/// greedily from the unit vectors.
pub(crate) fn complement(q: &DMatrix<f64>) -> DMatrix<f64> {
    let n = q.nrows();
    let mut basis: Vec<DVector<f64>> = q.column_iter().map(|c| c.into_owned()).collect();
    let mut added = Vec::new();
    while basis.len() < n {
        let mut best: Option<DVector<f64>> = None;
        for i in 0..n {
            let mut e = DVector::zeros(n);
            e[i] = 1.0;
            for _ in 0..2 {
                for b in &basis {
                    let proj = b.dot(&e);
                    e -= b * proj;
                }
            }
            let better = match &best {
                None => true,
                Some(b) => e.norm() > b.norm(),
            };
            if better {
                best = Some(e);
            }
        }
        let e = best.expect("n > 0");
        let e = &e / e.norm();
        basis.push(e.clone());
        added.push(e);
    }
    if added.is_empty() {
        DMatrix::zeros(n, 0)
    } else {
        DMatrix::from_columns(&added)
    }
}

/// States with weight ≥ 5 % of the largest in the subspace spanned by `basis` (columns).
pub(crate) fn spanning_states(basis: &DMatrix<f64>, names: &[String]) -> Vec<String> {
    let weight: Vec<f64> = basis.row_iter().map(|r| r.norm()).collect();
    let top = weight.iter().fold(0.0_f64, |m, &w| m.max(w));
    let mut idx: Vec<usize> = (0..weight.len())
        .filter(|&i| top > 0.0 && weight[i] >= 0.05 * top)
        .collect();
    idx.sort_by(|&x, &y| weight[y].total_cmp(&weight[x]));
    idx.into_iter().map(|i| names[i].clone()).collect()
}

impl SisoPlant {
    /// Reduces (A, b, c) to its minimal part. `names` are the state names (for the hidden
    /// parts).
    pub fn new(
        a: &DMatrix<f64>,
        b: &DVector<f64>,
        c: &RowDVector<f64>,
        names: &[String],
    ) -> Result<Self, LinearError> {
        let n = a.nrows();
        for (what, got) in [
            ("A columns", a.ncols()),
            ("b", b.len()),
            ("c", c.len()),
            ("state names", names.len()),
        ] {
            if got != n {
                return Err(LinearError::Dimension {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        check_finite("A", a.iter())?;
        check_finite("b", b.iter())?;
        check_finite("c", c.iter())?;
        if b.norm() == 0.0 {
            return Err(LinearError::ZeroInput);
        }
        let mut hidden = Vec::new();
        // Controllable subspace; A is block upper triangular in [Vc, Vc⊥].
        let vc = krylov_basis(a, b);
        let vu = complement(&vc);
        if vu.ncols() > 0 {
            let a22 = vu.transpose() * a * &vu;
            hidden.push(HiddenPart {
                kind: HiddenKind::Uncontrollable,
                eigenvalues: eigenvalues(&a22)?,
                states: spanning_states(&vu, names),
            });
        }
        let a1 = vc.transpose() * a * &vc;
        let b1 = vc.transpose() * b;
        let c1 = c * &vc;
        // Observable subspace of the controllable part: Krylov space of A1ᵀ from c1ᵀ.
        let wo = krylov_basis(&a1.transpose(), &c1.transpose());
        let wu = complement(&wo);
        if wu.ncols() > 0 {
            let a_un = wu.transpose() * &a1 * &wu;
            hidden.push(HiddenPart {
                kind: HiddenKind::Unobservable,
                eigenvalues: eigenvalues(&a_un)?,
                states: spanning_states(&(&vc * &wu), names),
            });
        }
        Ok(Self {
            a: wo.transpose() * &a1 * &wo,
            b: wo.transpose() * b1,
            c: c1 * &wo,
            hidden,
        })
    }

    /// Order of the minimal realisation.
    pub fn order(&self) -> usize {
        self.a.nrows()
    }

    /// The minimal realisation (A, b, c).
    pub fn realization(&self) -> (&DMatrix<f64>, &DVector<f64>, &RowDVector<f64>) {
        (&self.a, &self.b, &self.c)
    }

    /// The parts of the state the loop cannot move or see.
    pub fn hidden(&self) -> &[HiddenPart] {
        &self.hidden
    }

    /// Poles of the transfer function (eigenvalues of the minimal A).
    pub fn poles(&self) -> Result<Vec<Complex<f64>>, LinearError> {
        eigenvalues(&self.a)
    }

    /// P(s) = c (sI − A)⁻¹ b; `None` at a pole.
    pub fn eval(&self, s: Complex<f64>) -> Option<Complex<f64>> {
        let n = self.order();
        if n == 0 {
            return Some(Complex::new(0.0, 0.0));
        }
        let m = DMatrix::from_fn(n, n, |i, j| {
            Complex::new(-self.a[(i, j)], 0.0) + if i == j { s } else { Complex::new(0.0, 0.0) }
        });
        let rhs = DVector::from_fn(n, |i, _| Complex::new(self.b[i], 0.0));
        let x = m.lu().solve(&rhs)?;
        let y: Complex<f64> = (0..n).map(|i| x[i] * self.c[i]).sum();
        (y.re.is_finite() && y.im.is_finite()).then_some(y)
    }
}
