//! `audit`: a shipped vehicle's derived equations against twv's independent hand model and
//! physics (energy, momenta, symmetry), or any model against the user's own hand file, term by
//! term.

use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::options::{as_text, field, integer, is_none, number, Kind, Opt};
use super::{Job, JobOutput, Verdict};
use crate::api::{audit_hand, audit_model, HandSource};
use crate::audit::AuditReport;
use crate::error::Result;
use crate::hand_file::{HandAuditReport, HandAuditSettings};
use crate::model::ResolvedModel;
use crate::progress::Progress;

/// The audit.
pub struct Audit;

/// What to audit against and how hard.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AuditSettings {
    /// A hand file to audit against (read by the library); `None`: twv's own hand model.
    pub hand: Option<String>,
    /// The hand file's text instead of its path.
    pub hand_text: Option<String>,
    /// The name of `hand_text` in messages and the report. Default `hand file`.
    pub origin: String,
    /// The audit of a shipped vehicle against twv's hand model.
    pub derived: crate::audit::AuditSettings,
    /// The audit against a hand file.
    pub hand_audit: HandAuditSettings,
}

impl Default for AuditSettings {
    fn default() -> Self {
        Self {
            hand: None,
            hand_text: None,
            origin: "hand file".into(),
            derived: crate::audit::AuditSettings::default(),
            hand_audit: HandAuditSettings::default(),
        }
    }
}

/// Either report.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum AuditOutput {
    /// Against twv's hand model.
    Derived(AuditReport),
    /// Against a hand file.
    Hand(HandAuditReport),
}

impl AuditSettings {
    /// The hand file, if one is given.
    fn source(&self) -> Option<HandSource> {
        match (&self.hand, &self.hand_text) {
            (Some(path), _) => Some(HandSource::File(path.into())),
            (None, Some(text)) => Some(HandSource::Text {
                text: text.clone(),
                origin: self.origin.clone(),
            }),
            (None, None) => None,
        }
    }
}

fn optional_text(name: &'static str, v: &Value) -> Result<Option<String>> {
    Ok(if is_none(v) {
        None
    } else {
        Some(as_text(name, v)?.to_string())
    })
}

impl Job for Audit {
    const NAME: &'static str = "audit";
    const ALIASES: &'static [&'static str] = &["audit_hand"];
    const SUMMARY: &'static str = "Audit the derived model term by term against the independent \
        hand model, plus physical checks; with hand, any model against your own hand file";
    const SERVED: bool = false;
    type Settings = AuditSettings;
    type Output = AuditOutput;

    fn options() -> Vec<Opt<AuditSettings>> {
        vec![
            Opt::new(
                "hand",
                Kind::Text,
                "",
                "Your own hand model, a TOML file (M, Cp or C, F, Q and qdot, or f; docs: the \
                 hand-file format)",
                |s: &mut AuditSettings, v| {
                    s.hand = optional_text("hand", v)?;
                    Ok(())
                },
                |s| json!(s.hand),
            ),
            Opt::new(
                "hand_text",
                Kind::Text,
                "",
                "The hand file's text instead of a path",
                |s: &mut AuditSettings, v| {
                    s.hand_text = optional_text("hand_text", v)?;
                    Ok(())
                },
                |s| json!(s.hand_text),
            )
            .conflicts(&["hand"]),
            Opt::new(
                "origin",
                Kind::Text,
                "",
                "The name of hand_text in messages and the report",
                |s: &mut AuditSettings, v| {
                    s.origin = as_text("origin", v)?.to_string();
                    Ok(())
                },
                |s| Value::String(s.origin.clone()),
            ),
            Opt::new(
                "samples",
                Kind::Integer,
                "",
                "Random samples (states and inputs) besides the upright and hanging rest states",
                |s: &mut AuditSettings, v| {
                    let n = super::options::as_integer("samples", v)? as usize;
                    (s.derived.samples, s.hand_audit.samples) = (n, n);
                    Ok(())
                },
                |s| json!(s.derived.samples),
            ),
            Opt::new(
                "seed",
                Kind::Integer,
                "",
                "Seed of the samples",
                |s: &mut AuditSettings, v| {
                    let n = super::options::as_integer("seed", v)?;
                    (s.derived.seed, s.hand_audit.seed) = (n, n);
                    Ok(())
                },
                |s| json!(s.derived.seed),
            ),
            Opt::new(
                "tolerance",
                Kind::Number,
                "",
                "Largest accepted normwise relative error of a term",
                |s: &mut AuditSettings, v| {
                    let t = super::options::as_number("tolerance", v)?;
                    (s.derived.tolerance, s.hand_audit.tolerance) = (t, t);
                    Ok(())
                },
                |s| json!(s.derived.tolerance),
            ),
            number(
                "param_spread",
                "",
                "With a hand file: every second random sample varies each parameter by a factor \
                 in [1/SPREAD, SPREAD] (1: the given values only)",
                field(|s: &mut AuditSettings| &mut s.hand_audit.param_spread),
            ),
            integer(
                "simulations",
                "",
                "Without a hand file: nonlinear runs of the energy and momentum checks",
                field(|s: &mut AuditSettings| &mut s.derived.simulations),
            ),
        ]
    }

    fn validate(s: &AuditSettings) -> Result<()> {
        s.derived.validate()
    }

    fn run(model: &ResolvedModel, s: &AuditSettings, _p: &dyn Progress) -> Result<AuditOutput> {
        Self::validate(s)?;
        Ok(match s.source() {
            Some(hand) => AuditOutput::Hand(audit_hand(model, &hand, &s.hand_audit)?),
            None => AuditOutput::Derived(audit_model(model, &s.derived)?),
        })
    }
}

impl JobOutput for AuditOutput {
    fn summary(&self) -> String {
        match self {
            AuditOutput::Derived(r) => r.table(),
            AuditOutput::Hand(r) => r.table(),
        }
    }
    fn verdict(&self) -> Verdict {
        match self {
            AuditOutput::Derived(r) if !r.passed => {
                Verdict::Negative(format!("audit failed for {}", r.model))
            }
            AuditOutput::Hand(r) if !r.passed => Verdict::Negative(format!(
                "the hand file {} disagrees with the derivation of {} in {} entries",
                r.hand_file,
                r.model,
                r.disagreements.len()
            )),
            _ => Verdict::Done,
        }
    }
}
