//! Term-by-term comparison of two mechanical models: every entry of M, Cp, F, Q, f and ∂f/∂x.
//!
//! The error of an entry is measured against the size of its quantity at that sample
//! (normwise relative error |a − b| / max|b|): a structurally zero entry that one route gets as
//! round-off (1e-17) is then not reported as a huge relative error, while a dropped term of the
//! size of its neighbours is.

use serde::Serialize;
use twv_model::Mechanical;

use super::sampling::Sample;

/// Worst disagreement of one entry (one equation, or one matrix element) over all samples.
#[derive(Debug, Clone, Serialize)]
pub struct EntryError {
    /// e.g. `Cp[v_x]`, `M[w_y,v_x]`, `jac_x[w_z,phi]`.
    pub label: String,
    pub max_abs: f64,
    pub max_rel: f64,
    /// Index of the sample where `max_rel` occurred.
    pub worst_sample: usize,
}

/// Worst disagreement of one quantity, with its entries.
#[derive(Debug, Clone, Serialize)]
pub struct QuantityError {
    pub quantity: &'static str,
    pub max_abs: f64,
    pub max_rel: f64,
    pub worst_sample: usize,
    /// The entry with the largest relative error.
    pub worst_entry: String,
    pub entries: Vec<EntryError>,
}

/// Accumulates the errors of one quantity over the samples.
pub(crate) struct Tally {
    quantity: &'static str,
    entries: Vec<EntryError>,
}

impl Tally {
    pub(crate) fn new(quantity: &'static str, labels: Vec<String>) -> Self {
        let entries = labels
            .into_iter()
            .map(|label| EntryError {
                label,
                max_abs: 0.0,
                max_rel: 0.0,
                worst_sample: 0,
            })
            .collect();
        Self { quantity, entries }
    }

    /// Record one sample: `got` (the audited model) against `want` (the reference).
    pub(crate) fn add(&mut self, sample: usize, got: &[f64], want: &[f64]) {
        let scale = want.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let scale = if scale > 0.0 { scale } else { 1.0 };
        for ((entry, g), w) in self.entries.iter_mut().zip(got).zip(want) {
            let abs = (g - w).abs();
            // NaN compares false: treat a non-finite disagreement as infinitely wrong.
            let rel = if abs.is_nan() {
                f64::INFINITY
            } else {
                abs / scale
            };
            entry.max_abs = entry
                .max_abs
                .max(if abs.is_nan() { f64::INFINITY } else { abs });
            if rel > entry.max_rel {
                entry.max_rel = rel;
                entry.worst_sample = sample;
            }
        }
    }

    pub(crate) fn finish(self) -> QuantityError {
        let worst = self
            .entries
            .iter()
            .max_by(|a, b| a.max_rel.total_cmp(&b.max_rel))
            .cloned()
            .unwrap_or(EntryError {
                label: String::new(),
                max_abs: 0.0,
                max_rel: 0.0,
                worst_sample: 0,
            });
        QuantityError {
            quantity: self.quantity,
            max_abs: self.entries.iter().fold(0.0, |m, e| m.max(e.max_abs)),
            max_rel: worst.max_rel,
            worst_sample: worst.worst_sample,
            worst_entry: worst.label,
            entries: self.entries,
        }
    }
}

pub(crate) fn vector_labels(quantity: &str, names: &[&str]) -> Vec<String> {
    names.iter().map(|n| format!("{quantity}[{n}]")).collect()
}

pub(crate) fn matrix_labels(quantity: &str, rows: &[&str], cols: &[&str]) -> Vec<String> {
    rows.iter()
        .flat_map(|r| cols.iter().map(move |c| format!("{quantity}[{r},{c}]")))
        .collect()
}

fn flat<const R: usize, const C: usize>(m: &[[f64; C]; R]) -> Vec<f64> {
    m.iter().flatten().copied().collect()
}

/// Compare `audited` against `reference` at every sample, quantity by quantity.
pub fn compare<const NX: usize, const NU: usize, const NS: usize, A, R>(
    audited: &A,
    reference: &R,
    samples: &[Sample<NX, NU>],
) -> Vec<QuantityError>
where
    A: Mechanical<NX, NU, NS>,
    R: Mechanical<NX, NU, NS>,
{
    let info = reference.info();
    let states = info.states;
    let speeds = &states[NX - NS..];
    let mut tallies = [
        Tally::new("M", matrix_labels("M", speeds, speeds)),
        Tally::new("Cp", vector_labels("Cp", speeds)),
        Tally::new("F", vector_labels("F", speeds)),
        Tally::new("Q", vector_labels("Q", speeds)),
        Tally::new("f", vector_labels("f", states)),
        Tally::new("jac_x", matrix_labels("jac_x", states, states)),
    ];
    for (k, s) in samples.iter().enumerate() {
        let (mut ma, mut mr) = ([[0.0; NS]; NS], [[0.0; NS]; NS]);
        audited.mass_matrix(&s.x, &mut ma);
        reference.mass_matrix(&s.x, &mut mr);
        tallies[0].add(k, &flat(&ma), &flat(&mr));
        let (mut va, mut vr) = ([0.0; NS], [0.0; NS]);
        audited.cp(&s.x, &mut va);
        reference.cp(&s.x, &mut vr);
        tallies[1].add(k, &va, &vr);
        audited.gravity(&s.x, &mut va);
        reference.gravity(&s.x, &mut vr);
        tallies[2].add(k, &va, &vr);
        audited.input_forces(&s.x, &s.u, &mut va);
        reference.input_forces(&s.x, &s.u, &mut vr);
        tallies[3].add(k, &va, &vr);
        let (mut fa, mut fr) = ([0.0; NX], [0.0; NX]);
        audited.f(&s.x, &s.u, &mut fa);
        reference.f(&s.x, &s.u, &mut fr);
        tallies[4].add(k, &fa, &fr);
        let (mut ja, mut jr) = ([[0.0; NX]; NX], [[0.0; NX]; NX]);
        audited.jac_x(&s.x, &s.u, &mut ja);
        reference.jac_x(&s.x, &s.u, &mut jr);
        tallies[5].add(k, &flat(&ja), &flat(&jr));
    }
    tallies.into_iter().map(Tally::finish).collect()
}
