//! A user's hand model against the derivation: every entry of M, Cp, F, Q, f and ∂f/∂x at the
//! audit's samples, and for each disagreeing entry the symbolic difference hand − derived.

use std::fmt::Write;

use serde::Serialize;
use twv_ir::{Function, Ir};

use super::expr::{Args, Expr};
use super::file::{Entry, HandForm, HandModel};
use super::from_ir::entry_forms;
use super::normal::{normal_form, Names, Poly};
use crate::audit::compare::{matrix_labels, vector_labels, Tally};
use crate::audit::report::quantity_table;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::audit::{sample_vectors, AuditSettings, QuantityError};
use crate::error::{Error, Result};
use crate::hand_model::scalar::{solve_in_place, Dual, Real};

/// Settings of a hand-file audit, defaults beside each field.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HandAuditSettings {
    /// Random samples (after the upright and hanging rest states). Default 200.
    pub samples: usize,
    /// Seed of the samples. Default 2016.
    pub seed: u64,
    /// Largest accepted normwise relative error of any entry. Default 1e-11.
    pub tolerance: f64,
    /// Half-range of the random inputs (N or N m). Default 200.
    pub input_scale: f64,
    /// Every second random sample multiplies each parameter by a factor drawn log-uniformly in
    /// [1/spread, spread]: a wrong term that vanishes for this vehicle's values (I2_xx = I2_yy
    /// in vehicles/paper.toml hides a swapped inertia) still shows. 1 compares at the given
    /// values only. Default 2.
    pub param_spread: f64,
}

impl Default for HandAuditSettings {
    fn default() -> Self {
        let audit = AuditSettings::default();
        Self {
            samples: audit.samples,
            seed: audit.seed,
            tolerance: audit.tolerance,
            input_scale: audit.input_scale,
            param_spread: 2.0,
        }
    }
}

impl HandAuditSettings {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        AuditSettings {
            samples: self.samples,
            seed: self.seed,
            tolerance: self.tolerance,
            input_scale: self.input_scale,
            ..AuditSettings::default()
        }
        .validate()?;
        if !(self.param_spread.is_finite() && (1.0..=100.0).contains(&self.param_spread)) {
            return Err(Error::input(
                "param_spread",
                format!("{} must be in [1, 100]", self.param_spread),
            ));
        }
        Ok(())
    }
}

/// One entry that disagrees beyond the tolerance, where it is worst.
#[derive(Debug, Clone, Serialize)]
pub struct Disagreement {
    /// e.g. `Cp[v_x]`, `M[w_y,v_x]`.
    pub label: String,
    /// The line of the hand file the entry is on (0 for f and ∂f/∂x of the mechanical form).
    pub line: usize,
    pub max_rel: f64,
    pub max_abs: f64,
    /// The state and input where it is worst, by name.
    pub x: Vec<(String, f64)>,
    pub u: Vec<(String, f64)>,
    /// The parameters there when they were varied (empty: the given values).
    pub params: Vec<(String, f64)>,
    /// The largest relative error at the given parameter values alone: ≤ the tolerance means
    /// the entry holds for this vehicle's values but not as a formula.
    pub max_rel_at_given_params: f64,
    /// hand − derived, simplified (see `normal`), when the entry has a formula on both sides
    /// and is finite (the difference of a NaN entry may well simplify to 0).
    pub difference: Option<String>,
    /// `"hand"` or `"derived"` when that side's value is NaN or infinite at the worst sample.
    pub non_finite: Option<&'static str>,
}

/// Which model a side of the comparison (`audited`, `reference`) is in a hand audit.
pub(super) fn side_name(side: Option<&'static str>) -> Option<&'static str> {
    side.map(|s| if s == "audited" { "hand" } else { "derived" })
}

/// Everything an audit of a hand file found.
#[derive(Debug, Clone, Serialize)]
pub struct HandAuditReport {
    pub model: String,
    pub hand_file: String,
    /// `mechanical` (M, Cp, F, Q, q̇) or `f`.
    pub form: &'static str,
    pub samples: usize,
    pub seed: u64,
    pub tolerance: f64,
    pub param_spread: f64,
    pub quantities: Vec<QuantityError>,
    /// Every entry above the tolerance, in the order M, Cp, F, Q, f, ∂f/∂x: the first is the
    /// first disagreeing entry.
    pub disagreements: Vec<Disagreement>,
    /// Label of the entry with the largest relative error, if any disagrees.
    pub worst: Option<String>,
    pub passed: bool,
}

/// The derived model's quantities at one sample, dense.
pub(super) struct Derived<'a> {
    pub(super) ir: &'a Ir,
    pub(super) work: Vec<f64>,
}

impl Derived<'_> {
    pub(super) fn dense(
        &mut self,
        function: &str,
        x: &[f64],
        u: &[f64],
        p: &[f64],
    ) -> Result<Vec<f64>> {
        let f = self
            .ir
            .function(function)
            .ok_or_else(|| Error::Unsupported {
                model: self.ir.model().to_string(),
                reason: format!("its IR has no function {function}"),
            })?;
        let out = &f.outputs()[0];
        self.work.resize(f.n_values().max(self.work.len()), 0.0);
        f.eval(x, u, p, &mut self.work)
            .map_err(|e| Error::input("hand", e.to_string()))?;
        // Row-major dense from compressed columns.
        let mut dense = vec![0.0; out.rows * out.cols];
        for (row, col, value) in out.entries() {
            dense[row * out.cols + col] = self.work[value];
        }
        Ok(dense)
    }
}

/// The hand model's quantities at one sample, the same shapes as [`Derived::dense`].
struct Hand<'a> {
    form: &'a HandForm,
    nx: usize,
}

fn values<S: Real>(entries: &[Entry], args: &Args<'_, S>) -> Vec<S> {
    entries.iter().map(|e| e.expr.eval(args)).collect()
}

impl Hand<'_> {
    /// ẋ evaluated with number type S (f64 for values, Dual for one column of ∂f/∂x).
    fn f<S: Real>(&self, x: &[S], u: &[S], p: &[f64]) -> Vec<S> {
        let args = Args { x, u, p };
        match self.form {
            HandForm::Explicit { f } => values(f, &args),
            HandForm::Mechanical {
                mass,
                velocity,
                gravity,
                inputs,
                qdot,
                ..
            } => {
                let mut m: Vec<Vec<S>> = mass.iter().map(|row| values(row, &args)).collect();
                let (cp, g, q) = (
                    values(velocity, &args),
                    values(gravity, &args),
                    values(inputs, &args),
                );
                let mut rhs: Vec<S> = (0..cp.len()).map(|i| q[i] - cp[i] - g[i]).collect();
                solve_in_place(&mut m, &mut rhs);
                let mut out = values(qdot, &args);
                out.extend(rhs);
                out
            }
            // Audited about its steady motion by `linear`, never sampled here.
            HandForm::Linear { .. } => Vec::new(),
        }
    }

    /// ∂f/∂x row-major, one dual evaluation per column.
    fn jac_x(&self, x: &[f64], u: &[f64], p: &[f64]) -> Vec<f64> {
        let n = self.nx;
        let ud: Vec<Dual> = u.iter().map(|&v| Dual::new(v, 0.0)).collect();
        let mut jac = vec![0.0; n * n];
        for col in 0..n {
            let xd: Vec<Dual> = x
                .iter()
                .enumerate()
                .map(|(i, &v)| Dual::new(v, if i == col { 1.0 } else { 0.0 }))
                .collect();
            for (row, d) in self.f(&xd, &ud, p).iter().enumerate() {
                jac[row * n + col] = d.d;
            }
        }
        jac
    }
}

/// The hand entries of one quantity (an IR function of the same name), with their labels.
struct Quantity<'a> {
    name: &'static str,
    labels: Vec<String>,
    hand: Vec<&'a Entry>,
}

fn quantities<'a>(form: &'a HandForm, states: &[String], speeds: &[String]) -> Vec<Quantity<'a>> {
    let (states, speeds) = (refs(states), refs(speeds));
    let vector = |name, names: &[&str], hand: Vec<&'a Entry>| Quantity {
        name,
        labels: vector_labels(name, names),
        hand,
    };
    let matrix = |name, names: &[&str], hand: Vec<&'a Entry>| Quantity {
        name,
        labels: matrix_labels(name, names, names),
        hand,
    };
    match form {
        HandForm::Explicit { f } => vec![
            vector("f", &states, f.iter().collect()),
            matrix("jac_x", &states, vec![]),
        ],
        HandForm::Mechanical {
            mass,
            velocity,
            gravity,
            inputs,
            qdot,
            ..
        } => vec![
            matrix("M", &speeds, mass.iter().flatten().collect()),
            vector("Cp", &speeds, velocity.iter().collect()),
            vector("F", &speeds, gravity.iter().collect()),
            vector("Q", &speeds, inputs.iter().collect()),
            // The coordinate rows of f are the file's q̇; its speed rows have no one formula.
            vector("f", &states, qdot.iter().collect()),
            matrix("jac_x", &states, vec![]),
        ],
        HandForm::Linear { .. } => vec![],
    }
}

fn refs(names: &[String]) -> Vec<&str> {
    names.iter().map(String::as_str).collect()
}

fn named(names: &[String], values: &[f64]) -> Vec<(String, f64)> {
    names.iter().cloned().zip(values.iter().copied()).collect()
}

/// hand − derived for entry `index` of `function`'s output, simplified; `None` when either side
/// has no formula or does not expand within bounds.
fn difference(
    hand: &Expr,
    function: &Function,
    index: usize,
    names: &Names<'_>,
    forms: &mut Option<Vec<Option<Poly>>>,
) -> Option<String> {
    let forms = forms.get_or_insert_with(|| {
        let out = &function.outputs()[0];
        let stored = entry_forms(function, &out.name, names);
        // Dense, row-major, structural zeros as the zero polynomial.
        let mut dense = vec![Some(Poly::default()); out.rows * out.cols];
        for ((row, col, _), form) in out.entries().zip(stored) {
            dense[row * out.cols + col] = form.ok();
        }
        dense
    });
    let derived = forms.get(index)?.as_ref()?;
    let hand = normal_form(hand, names).ok()?;
    Some(hand.difference(derived).print(names))
}

/// The parameters of each sample: the given values, and for every second random sample each
/// value times a factor log-uniform in [1/spread, spread] (its own stream, so that the states
/// are those of the built-in audit for the same seed).
pub(super) fn sample_params(
    params: &[f64],
    n: usize,
    settings: &HandAuditSettings,
) -> Vec<Option<Vec<f64>>> {
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed ^ 0x005e_ed0f_ba5e);
    let ln = settings.param_spread.ln();
    (0..n)
        .map(|k| {
            (k >= 2 && k % 2 == 1 && ln > 0.0).then(|| {
                params
                    .iter()
                    .map(|p| p * rng.gen_range(-ln..ln).exp())
                    .collect()
            })
        })
        .collect()
}

/// The parameters the model uses with their values, where a sample varied them (empty: the
/// given values).
pub(super) fn used_params(ir: &Ir, varied: Option<&[f64]>) -> Vec<(String, f64)> {
    varied
        .map(|p| {
            ir.params()
                .iter()
                .zip(p)
                .filter(|(param, _)| param.used)
                .map(|(param, v)| (param.name.clone(), *v))
                .collect()
        })
        .unwrap_or_default()
}

/// Audits the hand model `hand` against the derived model (`ir` with `params`, the interpreter:
/// the same bits as the generated code).
pub fn audit_hand_model(
    ir: &Ir,
    params: &[f64],
    hand: &HandModel,
    settings: &HandAuditSettings,
) -> Result<HandAuditReport> {
    settings.validate()?;
    if let HandForm::Linear { .. } = hand.form {
        return super::linear::audit_linear(ir, params, hand, settings);
    }
    let states: Vec<String> = ir.states().iter().map(|s| s.name.clone()).collect();
    let inputs: Vec<String> = ir.inputs().iter().map(|s| s.name.clone()).collect();
    let param_names: Vec<String> = ir.params().iter().map(|p| p.name.clone()).collect();
    let speeds: Vec<String> = ir.mechanics().map_or(vec![], |m| m.speeds.clone());
    let samples = sample_vectors(
        &states,
        inputs.len(),
        settings.input_scale,
        settings.samples + 2,
        settings.seed,
    );
    let varied = sample_params(params, samples.len(), settings);
    let mut derived = Derived {
        ir,
        work: Vec::new(),
    };
    let evaluator = Hand {
        form: &hand.form,
        nx: states.len(),
    };
    let plan = quantities(&hand.form, &states, &speeds);
    let tallies = || -> Vec<Tally> {
        plan.iter()
            .map(|q| Tally::new(q.name, q.labels.clone()))
            .collect()
    };
    // Over every sample, and over the samples at the given parameters alone.
    let (mut all, mut given) = (tallies(), tallies());
    for (k, ((x, u), varied)) in samples.iter().zip(&varied).enumerate() {
        let p = varied.as_deref().unwrap_or(params);
        let args = Args { x, u, p };
        for (i, q) in plan.iter().enumerate() {
            let want = derived.dense(q.name, x, u, p)?;
            let got: Vec<f64> = match q.name {
                "f" => evaluator.f(x, u, p),
                "jac_x" => evaluator.jac_x(x, u, p),
                _ => q.hand.iter().map(|e| e.expr.eval(&args)).collect(),
            };
            all[i].add(k, &got, &want);
            if varied.is_none() {
                given[i].add(k, &got, &want);
            }
        }
    }
    let quantities: Vec<QuantityError> = all.into_iter().map(Tally::finish).collect();
    let at_given: Vec<QuantityError> = given.into_iter().map(Tally::finish).collect();
    let names = Names {
        states: &states,
        inputs: &inputs,
        params: &param_names,
    };
    let mut disagreements = Vec::new();
    for ((quantity, q), given) in quantities.iter().zip(&plan).zip(&at_given) {
        let function = ir.function(q.name);
        let mut forms = None;
        for (index, entry) in quantity.entries.iter().enumerate() {
            // Asked this way round so that a NaN error disagrees.
            if entry.max_rel <= settings.tolerance {
                continue;
            }
            let hand_entry = q.hand.get(index);
            let (x, u) = &samples[entry.worst_sample];
            let worst_params = used_params(ir, varied[entry.worst_sample].as_deref());
            disagreements.push(Disagreement {
                label: entry.label.clone(),
                line: hand_entry.map_or(0, |e| e.line),
                max_rel: entry.max_rel,
                max_abs: entry.max_abs,
                x: named(&states, x),
                u: named(&inputs, u),
                params: worst_params,
                max_rel_at_given_params: given.entries[index].max_rel,
                difference: match (hand_entry, function, entry.non_finite) {
                    (Some(e), Some(f), None) => difference(&e.expr, f, index, &names, &mut forms),
                    _ => None,
                },
                non_finite: side_name(entry.non_finite),
            });
        }
    }
    let form = match hand.form {
        HandForm::Explicit { .. } => "f",
        HandForm::Mechanical { .. } => "mechanical",
        HandForm::Linear { .. } => "linear",
    };
    Ok(HandAuditReport::from_parts(
        (ir, hand, form),
        samples.len(),
        settings,
        quantities,
        disagreements,
    ))
}

impl HandAuditReport {
    /// The report of an audit of `hand` (in `form`) against `ir`: the worst entry and the
    /// verdict from the disagreements.
    pub(super) fn from_parts(
        (ir, hand, form): (&Ir, &HandModel, &'static str),
        samples: usize,
        settings: &HandAuditSettings,
        quantities: Vec<QuantityError>,
        disagreements: Vec<Disagreement>,
    ) -> Self {
        let worst = disagreements
            .iter()
            .max_by(|a, b| a.max_rel.total_cmp(&b.max_rel))
            .map(|d| d.label.clone());
        Self {
            model: ir.model().to_string(),
            hand_file: hand.origin.clone(),
            form,
            samples,
            seed: settings.seed,
            tolerance: settings.tolerance,
            param_spread: settings.param_spread,
            quantities,
            passed: disagreements.is_empty(),
            disagreements,
            worst,
        }
    }
}

fn format_named(values: &[(String, f64)]) -> String {
    let parts: Vec<String> = values
        .iter()
        .map(|(n, v)| format!("{n} = {v:.4}"))
        .collect();
    parts.join(", ")
}

impl Disagreement {
    fn describe(&self, tolerance: f64) -> String {
        let line = match self.line {
            0 => String::new(),
            n => format!(" (line {n})"),
        };
        let at = if self.x.is_empty() { "" } else { " at " };
        let what = match self.non_finite {
            Some(side) => format!("the {side} value is not finite (NaN or infinite)"),
            None => format!("relative error {:.3e}", self.max_rel),
        };
        let mut text = format!(
            "{}{line}: {what}{at}{}{}{}",
            self.label,
            format_named(&self.x),
            if self.u.is_empty() { "" } else { "; " },
            format_named(&self.u)
        );
        if !self.params.is_empty() {
            let _ = write!(text, "; parameters varied: {}", format_named(&self.params));
        }
        if self.max_rel_at_given_params <= tolerance {
            let _ = write!(
                text,
                " (at the given parameters {:.1e}: it holds for these values, not as a formula)",
                self.max_rel_at_given_params
            );
        }
        text
    }
}

impl HandAuditReport {
    /// The table printed by `twv audit --hand`.
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "audit {} against the hand file {} ({} form): {} samples (seed {}, every second with the \
             parameters varied ×/÷ {}), tolerance {:.0e} relative",
            self.model,
            self.hand_file,
            self.form,
            self.samples,
            self.seed,
            self.param_spread,
            self.tolerance
        );
        s.push_str(&quantity_table(&self.quantities, self.tolerance));
        let (Some(first), Some(worst)) = (
            self.disagreements.first(),
            self.disagreements
                .iter()
                .find(|d| Some(&d.label) == self.worst.as_ref()),
        ) else {
            let _ = writeln!(
                s,
                "  PASSED: every entry agrees within {:.0e}",
                self.tolerance
            );
            return s;
        };
        let _ = writeln!(
            s,
            "  FAILED: {} entries disagree beyond {:.0e}",
            self.disagreements.len(),
            self.tolerance
        );
        let _ = writeln!(s, "  first: {}", first.describe(self.tolerance));
        let _ = writeln!(s, "  worst: {}", worst.describe(self.tolerance));
        let with_formula: Vec<&Disagreement> = self
            .disagreements
            .iter()
            .filter(|d| d.difference.is_some())
            .collect();
        if !with_formula.is_empty() {
            let _ = writeln!(s, "  hand − derived, simplified:");
            for d in with_formula {
                let _ = writeln!(
                    s,
                    "    {} = {}",
                    d.label,
                    d.difference.as_deref().unwrap_or_default()
                );
            }
        }
        s
    }
}
