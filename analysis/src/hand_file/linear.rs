//! A hand file in the linear form — M q̈ + v C1 q̇ + (g K0 + v² K2) q = f about the model's steady
//! motion, the form of the Whipple bicycle benchmark (Meijaard et al. 2007) — against the
//! derivation.
//!
//! The derived side is the linearisation of the derived nonlinear equations, taken from the IR:
//! M is the modes' block of the mass matrix at the steady motion, and with A(v) the Jacobian
//! restricted to the modes at speed v, K(v) = −M A(v)[rates, coordinates] = g K0 + v² K2 and
//! C(v) = −M A(v)[rates, rates] = v C1, so K0 = K(0)/g, K2 = K(1) − K(0), C1 = C(1). Because the
//! derived model need not be of that form, the state matrices A(v) of both sides are compared
//! too, at speeds 0, 1, …, 10 m/s (one per sample). Every second sample varies the parameters
//! as the nonlinear audit does. The derived matrices hold M⁻¹ inside, so a disagreement has no
//! symbolic difference; its line and the parameters where it is worst are reported.

use nalgebra::DMatrix;

use super::audit::{
    sample_params, used_params, Derived, Disagreement, HandAuditReport, HandAuditSettings,
};
use super::expr::Args;
use super::file::{Entry, HandForm, HandModel};
use crate::audit::compare::{matrix_labels, Tally};
use crate::audit::QuantityError;
use crate::error::{Error, Result};
use twv_ir::Ir;

/// The speed of sample k [m/s]: 0, 1, …, 10, 0, 1, …
fn sample_speed(k: usize) -> f64 {
    (k % 11) as f64
}

/// The linear form's matrices at one parameter vector.
struct Linear {
    mass: DMatrix<f64>,
    c1: DMatrix<f64>,
    k0: DMatrix<f64>,
    k2: DMatrix<f64>,
}

impl Linear {
    /// A(v) of x' = A x for x = (q, q̇), or `None` when M is singular.
    fn state_matrix(&self, g: f64, v: f64) -> Option<DMatrix<f64>> {
        let n = self.mass.nrows();
        let minv = self.mass.clone().try_inverse()?;
        let mut a = DMatrix::zeros(2 * n, 2 * n);
        a.view_mut((0, n), (n, n)).fill_with_identity();
        a.view_mut((n, 0), (n, n))
            .copy_from(&(-&minv * (&self.k0 * g + &self.k2 * (v * v))));
        a.view_mut((n, n), (n, n))
            .copy_from(&(-&minv * (&self.c1 * v)));
        Some(a)
    }
}

/// Row-major values of a matrix, the order of `matrix_labels`.
fn row_major(m: &DMatrix<f64>) -> Vec<f64> {
    m.transpose().as_slice().to_vec()
}

fn hand_matrix(rows: &[Vec<Entry>], p: &[f64]) -> DMatrix<f64> {
    let args = Args::<f64> { x: &[], u: &[], p };
    let n = rows.len();
    DMatrix::from_fn(n, n, |i, j| rows[i][j].expr.eval(&args))
}

/// The derived model's linearisation about its steady motion at parameters `p`.
struct DerivedLinear<'a> {
    derived: Derived<'a>,
    /// State indices of the modes: coordinates, then rates.
    modes: Vec<usize>,
    /// Indices of the rates among the model's speeds (rows and columns of its M).
    rate_speeds: Vec<usize>,
    g: usize,
}

impl DerivedLinear<'_> {
    /// The steady motion's state at unit speed (the IR's `steady`) at parameters `p`.
    fn unit_state(&mut self, p: &[f64]) -> Result<Vec<f64>> {
        let ir = self.derived.ir;
        let (x, u) = (vec![0.0; ir.nx()], vec![0.0; ir.nu()]);
        self.derived.dense("steady", &x, &u, p)
    }

    /// A(v) restricted to the modes, at the steady motion `v · unit`.
    fn state_matrix(&mut self, unit: &[f64], v: f64, p: &[f64]) -> Result<DMatrix<f64>> {
        let ir = self.derived.ir;
        let x: Vec<f64> = unit.iter().map(|s| v * s).collect();
        let jac = self.derived.dense("jac_x", &x, &vec![0.0; ir.nu()], p)?;
        let (n, modes) = (ir.nx(), &self.modes);
        Ok(DMatrix::from_fn(modes.len(), modes.len(), |i, j| {
            jac[modes[i] * n + modes[j]]
        }))
    }

    fn matrices(&mut self, unit: &[f64], p: &[f64]) -> Result<Linear> {
        let ir = self.derived.ir;
        let rest = vec![0.0; unit.len()];
        let full = self.derived.dense("M", &rest, &vec![0.0; ir.nu()], p)?;
        let ns = ir.ns();
        let r = &self.rate_speeds;
        let mass = DMatrix::from_fn(r.len(), r.len(), |i, j| full[r[i] * ns + r[j]]);
        let half = r.len();
        let (a0, a1) = (
            self.state_matrix(unit, 0.0, p)?,
            self.state_matrix(unit, 1.0, p)?,
        );
        let stiffness = |a: &DMatrix<f64>| -&mass * a.view((half, 0), (half, half));
        let damping = |a: &DMatrix<f64>| -&mass * a.view((half, half), (half, half));
        let (k_0, k_1) = (stiffness(&a0), stiffness(&a1));
        Ok(Linear {
            c1: damping(&a1),
            k0: &k_0 / p[self.g],
            k2: k_1 - k_0,
            mass,
        })
    }
}

/// Audits a linear-form hand file against the derived model `ir` with `params`.
pub(super) fn audit_linear(
    ir: &Ir,
    params: &[f64],
    hand: &HandModel,
    settings: &HandAuditSettings,
) -> Result<HandAuditReport> {
    let HandForm::Linear {
        coordinates,
        rates,
        mass,
        c1,
        k0,
        k2,
    } = &hand.form
    else {
        return Err(Error::input("hand", "not a linear-form hand file"));
    };
    let unsupported = |reason: String| Error::Unsupported {
        model: ir.model().to_string(),
        reason,
    };
    let index = |names: &[String], name: &str| names.iter().position(|n| n == name);
    let states: Vec<String> = ir.states().iter().map(|s| s.name.clone()).collect();
    let speeds = ir.mechanics().map_or(vec![], |m| m.speeds.clone());
    let params_named: Vec<String> = ir.params().iter().map(|p| p.name.clone()).collect();
    let modes = coordinates
        .iter()
        .chain(rates)
        .map(|n| index(&states, n).ok_or_else(|| unsupported(format!("mode `{n}` is no state"))))
        .collect::<Result<Vec<_>>>()?;
    let rate_speeds = rates
        .iter()
        .map(|n| index(&speeds, n).ok_or_else(|| unsupported(format!("rate `{n}` is no speed"))))
        .collect::<Result<Vec<_>>>()?;
    let g = index(&params_named, "g").ok_or_else(|| {
        unsupported("the linear form's g K0 needs a parameter named `g`".to_string())
    })?;
    let mut derived = DerivedLinear {
        derived: Derived {
            ir,
            work: Vec::new(),
        },
        modes,
        rate_speeds,
        g,
    };

    let n = settings.samples + 2;
    let varied = sample_params(params, n, settings);
    let mode_names: Vec<&str> = coordinates
        .iter()
        .chain(rates)
        .map(String::as_str)
        .collect();
    let q: Vec<&str> = coordinates.iter().map(String::as_str).collect();
    let plan: [(&'static str, Option<&Vec<Vec<Entry>>>); 5] = [
        ("M", Some(mass)),
        ("C1", Some(c1)),
        ("K0", Some(k0)),
        ("K2", Some(k2)),
        ("A", None),
    ];
    let tallies = || -> Vec<Tally> {
        plan.iter()
            .map(|(name, _)| match name {
                &"A" => Tally::new("A", matrix_labels("A", &mode_names, &mode_names)),
                name => Tally::new(name, matrix_labels(name, &q, &q)),
            })
            .collect()
    };
    let (mut all, mut given) = (tallies(), tallies());
    for (k, varied_p) in varied.iter().enumerate() {
        let p = varied_p.as_deref().unwrap_or(params);
        let unit = derived.unit_state(p)?;
        let want = derived.matrices(&unit, p)?;
        let got = Linear {
            mass: hand_matrix(mass, p),
            c1: hand_matrix(c1, p),
            k0: hand_matrix(k0, p),
            k2: hand_matrix(k2, p),
        };
        let v = sample_speed(k);
        let a_want = derived.state_matrix(&unit, v, p)?;
        let a_got = got
            .state_matrix(p[g], v)
            .unwrap_or_else(|| DMatrix::from_element(a_want.nrows(), a_want.ncols(), f64::NAN));
        let pairs = [
            (&got.mass, &want.mass),
            (&got.c1, &want.c1),
            (&got.k0, &want.k0),
            (&got.k2, &want.k2),
            (&a_got, &a_want),
        ];
        for (i, (h, d)) in pairs.iter().enumerate() {
            all[i].add(k, &row_major(h), &row_major(d));
            if varied_p.is_none() {
                given[i].add(k, &row_major(h), &row_major(d));
            }
        }
    }
    let quantities: Vec<QuantityError> = all.into_iter().map(Tally::finish).collect();
    let at_given: Vec<QuantityError> = given.into_iter().map(Tally::finish).collect();
    let mut disagreements = Vec::new();
    for ((quantity, (_, entries)), given) in quantities.iter().zip(&plan).zip(&at_given) {
        for (index, entry) in quantity.entries.iter().enumerate() {
            // Asked this way round so that a NaN error disagrees.
            if entry.max_rel <= settings.tolerance {
                continue;
            }
            let line = entries
                .and_then(|rows| rows.iter().flatten().nth(index))
                .map_or(0, |e| e.line);
            let worst_params = used_params(ir, varied[entry.worst_sample].as_deref());
            disagreements.push(Disagreement {
                label: entry.label.clone(),
                line,
                max_rel: entry.max_rel,
                max_abs: entry.max_abs,
                x: if entries.is_none() {
                    vec![("v".to_string(), sample_speed(entry.worst_sample))]
                } else {
                    vec![]
                },
                u: vec![],
                params: worst_params,
                max_rel_at_given_params: given.entries[index].max_rel,
                difference: None,
                non_finite: super::audit::side_name(entry.non_finite),
            });
        }
    }
    Ok(HandAuditReport::from_parts(
        (ir, hand, "linear"),
        n,
        settings,
        quantities,
        disagreements,
    ))
}
