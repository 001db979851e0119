//! One convex subproblem of the tuner, solved by Clarabel:
//! minimise ½ xᵀ diag(p) x + qᵀ x subject to rows·x ≥ rhs and lower ≤ x ≤ upper.
//! Small (2–4 variables, a few hundred rows), so the matrices are built densely.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

/// A subproblem: diagonal quadratic objective and linear inequalities.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Subproblem {
    /// Diagonal of the quadratic term (may be all zero: an LP).
    pub p_diag: Vec<f64>,
    /// Linear term.
    pub q: Vec<f64>,
    /// Rows a with a·x ≥ rhs.
    pub rows: Vec<Vec<f64>>,
    /// Right-hand sides.
    pub rhs: Vec<f64>,
    /// Lower bounds.
    pub lower: Vec<f64>,
    /// Upper bounds.
    pub upper: Vec<f64>,
}

/// How a subproblem ended.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum SubOutcome {
    /// Solved (or solved to reduced accuracy); the minimiser.
    Solved(Vec<f64>),
    /// Clarabel's status otherwise (infeasible, numerical trouble, …).
    Failed(String),
}

/// Solves the subproblem with Clarabel.
pub(crate) fn solve(sub: &Subproblem) -> SubOutcome {
    let n = sub.q.len();
    // Clarabel form: A x + s = b, s ≥ 0. a·x ≥ rhs  ⇔  −a·x + s = −rhs.
    let mut dense: Vec<Vec<f64>> = Vec::with_capacity(sub.rows.len() + 2 * n);
    let mut b = Vec::with_capacity(sub.rows.len() + 2 * n);
    for (row, &r) in sub.rows.iter().zip(&sub.rhs) {
        dense.push(row.iter().map(|v| -v).collect());
        b.push(-r);
    }
    for j in 0..n {
        let mut lo = vec![0.0; n];
        lo[j] = -1.0;
        dense.push(lo);
        b.push(-sub.lower[j]);
        let mut hi = vec![0.0; n];
        hi[j] = 1.0;
        dense.push(hi);
        b.push(sub.upper[j]);
    }
    let a = CscMatrix::from(&dense);
    let p = {
        let mut d = vec![vec![0.0; n]; n];
        for (j, &v) in sub.p_diag.iter().enumerate() {
            d[j][j] = v;
        }
        CscMatrix::from(&d)
    };
    let cones = [SupportedConeT::NonnegativeConeT(b.len())];
    let Ok(settings) = DefaultSettingsBuilder::default()
        .verbose(false)
        .max_iter(200)
        .build()
    else {
        return SubOutcome::Failed("settings".into());
    };
    let mut solver = match DefaultSolver::new(&p, &sub.q, &a, &b, &cones, settings) {
        Ok(s) => s,
        Err(e) => return SubOutcome::Failed(e.to_string()),
    };
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {
            SubOutcome::Solved(solver.solution.x.clone())
        }
        other => SubOutcome::Failed(format!("{other:?}")),
    }
}
