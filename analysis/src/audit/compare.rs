//! Term-by-term comparison of two mechanical models: every entry of M, Cp, F, Q, f and ∂f/∂x.
//!
//! The error of an entry is measured against the size of its quantity at that sample
//! (normwise relative error |a − b| / max|b|): a structurally zero entry that one route gets as
//! round-off (1e-17) is then not reported as a huge relative error, while a dropped term of the
//! size of its neighbours is. The size is floored by [`FLOOR`] times the entry's own largest
//! magnitude over all samples: at a rest state where the whole quantity is round-off (the
//! gravity forces hanging down, `sin(pi - phi)` at phi = pi), round-off cannot fail a correct
//! formula, while a wrong one still shows in full at every sample where the entry is not small.

use serde::Serialize;
use twv_model::Mechanical;

use super::sampling::Sample;

/// The floor of an entry's size, as a fraction of its largest magnitude over the samples: round-off
/// (1e-16 of the terms) over it is far below any tolerance, and it is far below the size of
/// the entry wherever the entry is not itself nearly zero.
pub const FLOOR: f64 = 1e-3;

/// Worst disagreement of one entry (one equation, or one matrix element) over all samples.
#[derive(Debug, Clone, Serialize)]
pub struct EntryError {
    /// e.g. `Cp[v_x]`, `M[w_y,v_x]`, `jac_x[w_z,phi]`.
    pub label: String,
    pub max_abs: f64,
    pub max_rel: f64,
    /// Index of the sample where `max_rel` occurred.
    pub worst_sample: usize,
    /// `"audited"` or `"reference"` when that side's value was NaN or infinite at some sample
    /// (`worst_sample` is the first such one): the entry is then not finite, not merely far off.
    pub non_finite: Option<&'static str>,
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

/// One entry at one sample: (sample, |got − want|, the quantity's size, the side not finite).
type SampleError = (usize, f64, f64, Option<&'static str>);

/// Accumulates the errors of one quantity over the samples; the relative errors are formed at
/// the end, when every entry's floor is known.
pub(crate) struct Tally {
    quantity: &'static str,
    labels: Vec<String>,
    /// Per entry, per sample: (sample, |got − want| (∞ if either is not finite), the quantity's
    /// size at the sample, the side that was not finite).
    errors: Vec<Vec<SampleError>>,
    /// Per entry: its largest |want| over the samples.
    floor: Vec<f64>,
}

impl Tally {
    pub(crate) fn new(quantity: &'static str, labels: Vec<String>) -> Self {
        let n = labels.len();
        Self {
            quantity,
            labels,
            errors: vec![Vec::new(); n],
            floor: vec![0.0; n],
        }
    }

    /// Record one sample: `got` (the audited model) against `want` (the reference).
    pub(crate) fn add(&mut self, sample: usize, got: &[f64], want: &[f64]) {
        let scale = want
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0_f64, |m, v| m.max(v.abs()));
        for (i, (g, w)) in got.iter().zip(want).enumerate().take(self.labels.len()) {
            let side = match (g.is_finite(), w.is_finite()) {
                (true, true) => None,
                (false, _) => Some("audited"),
                (true, false) => Some("reference"),
            };
            let abs = if side.is_none() {
                (g - w).abs()
            } else {
                f64::INFINITY
            };
            if w.is_finite() {
                self.floor[i] = self.floor[i].max(w.abs());
            }
            self.errors[i].push((sample, abs, scale, side));
        }
    }

    pub(crate) fn finish(self) -> QuantityError {
        let entries: Vec<EntryError> = self
            .labels
            .into_iter()
            .zip(self.errors)
            .zip(self.floor)
            .map(|((label, errors), floor)| {
                let mut entry = EntryError {
                    label,
                    max_abs: 0.0,
                    max_rel: 0.0,
                    worst_sample: 0,
                    non_finite: None,
                };
                for (sample, abs, scale, side) in errors {
                    let size = scale.max(FLOOR * floor);
                    let rel = abs / if size > 0.0 { size } else { 1.0 };
                    entry.max_abs = entry.max_abs.max(abs);
                    if rel > entry.max_rel {
                        entry.max_rel = rel;
                        entry.worst_sample = sample;
                        entry.non_finite = side;
                    }
                }
                entry
            })
            .collect();
        let worst = entries
            .iter()
            .max_by(|a, b| a.max_rel.total_cmp(&b.max_rel))
            .cloned();
        QuantityError {
            quantity: self.quantity,
            max_abs: entries.iter().fold(0.0, |m, e| m.max(e.max_abs)),
            max_rel: worst.as_ref().map_or(0.0, |w| w.max_rel),
            worst_sample: worst.as_ref().map_or(0, |w| w.worst_sample),
            worst_entry: worst.map(|w| w.label).unwrap_or_default(),
            entries,
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
