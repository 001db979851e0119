//! The library's error: every way a job can refuse its input or fail, each naming the file,
//! field or value. How a run *ended* (fell, not converged, infeasible) is a status in the
//! result, not an error.

use std::path::PathBuf;

/// Why a job could not run.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A model IR that does not read or validate.
    #[error(transparent)]
    Ir(#[from] twv_ir::IrError),
    /// A parameter file or value that does not read or validate.
    #[error(transparent)]
    Params(#[from] twv_ir::ParamError),
    /// A model that cannot be built with these sizes or values.
    #[error(transparent)]
    Model(#[from] twv_ir::ModelError),
    /// An IR whose sizes the interpreter does not dispatch.
    #[error(transparent)]
    Size(#[from] twv_ir::UnsupportedSize),
    /// No shipped model of that name.
    #[error("unknown model `{name}` (shipped: {known})")]
    UnknownModel {
        /// The name asked for.
        name: String,
        /// The shipped names, comma-separated.
        known: String,
    },
    /// A setting or input vector that is missing, malformed or out of range.
    #[error("{field}: {reason}")]
    Input {
        /// The setting (the CLI option without its dashes).
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// A job asked of a model that cannot do it (no pitch to control, no mechanics to audit).
    #[error("model `{model}`: {reason}")]
    Unsupported {
        /// Model name.
        model: String,
        /// Why not.
        reason: String,
    },
    /// A result that came out NaN or infinite.
    #[error("{what} is not finite at {at}: the model is singular or overflows there")]
    NonFinite {
        /// Which output.
        what: String,
        /// The state (and input) it was evaluated at.
        at: String,
    },
    /// Lyapunov settings or run.
    #[error(transparent)]
    Lyapunov(#[from] crate::lyapunov::LyapunovError),
    /// Lyapunov settings alone.
    #[error("invalid Lyapunov settings")]
    LyapunovSettings(#[from] crate::lyapunov::SettingsError),
    /// Controller settings or a closed-loop run.
    #[error(transparent)]
    Control(#[from] crate::control::ControlError),
    /// Linear analysis.
    #[error(transparent)]
    Linear(#[from] crate::linear::LinearError),
    /// The tuner's input.
    #[error(transparent)]
    Tune(#[from] crate::tune::TuneError),
    /// A tuning specification that does not read.
    #[error(transparent)]
    Spec(#[from] crate::tune::SpecError),
    /// Sweep grids, shards and merges.
    #[error(transparent)]
    Sweep(#[from] crate::sweep::SweepError),
    /// An integration that failed.
    #[error(transparent)]
    Integrate(#[from] crate::integrate::IntegrateError),
    /// Code generation.
    #[error(transparent)]
    Emit(#[from] twv_emit::EmitError),
    /// A figure that could not be drawn.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
    /// Writing results.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// Reading an input file.
    #[error("cannot read {path}: {reason}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// A user's hand file that does not read or does not fit the model.
    #[error(transparent)]
    HandFile(#[from] crate::hand_file::HandFileError),
    /// The caller cancelled the run (Ctrl-C).
    #[error("interrupted")]
    Interrupted,
}

impl Error {
    /// Whether the run stopped because the caller cancelled it (whichever part noticed).
    pub fn is_interrupted(&self) -> bool {
        matches!(
            self,
            Error::Interrupted
                | Error::Lyapunov(crate::lyapunov::LyapunovError::Interrupted)
                | Error::Control(crate::control::ControlError::Interrupted)
                | Error::Tune(crate::tune::TuneError::Interrupted)
        )
    }

    /// A bad setting or input.
    pub fn input(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Input {
            field: field.into(),
            reason: reason.into(),
        }
    }
}

/// `text` with every decimal number longer than [`LONGEST_NUMBER`] characters (Rust prints
/// 1e300 as 301 digits) rewritten in scientific notation, for messages people read.
pub fn readable_numbers(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        out.push_str(&rest[..start]);
        let tail = &rest[start..];
        let int_len = tail
            .find(|c: char| !c.is_ascii_digit())
            .unwrap_or(tail.len());
        let mut end = int_len;
        if tail[int_len..].starts_with('.') {
            let fraction = &tail[int_len + 1..];
            let digits = fraction
                .find(|c: char| !c.is_ascii_digit())
                .unwrap_or(fraction.len());
            if digits > 0 {
                end = int_len + 1 + digits;
            }
        }
        let number = &tail[..end];
        match number.parse::<f64>() {
            Ok(v) if number.len() > LONGEST_NUMBER => out.push_str(&format!("{v:e}")),
            _ => out.push_str(number),
        }
        rest = &tail[end..];
    }
    out.push_str(rest);
    out
}

/// Numbers in messages longer than this are shortened by [`readable_numbers`].
pub const LONGEST_NUMBER: usize = 24;

/// `text` for a message of one line: numbers readable ([`readable_numbers`]) and control
/// characters (a newline in a field name a request sent) escaped as `\n`, so that a message
/// can never be more than one line nor carry a terminal's control sequences.
pub fn readable(text: &str) -> String {
    let mut escaped = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() {
            escaped.extend(c.escape_default());
        } else {
            escaped.push(c);
        }
    }
    readable_numbers(&escaped)
}

/// An error and its causes on one line, numbers readable: what every front end shows.
pub fn one_line(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text = format!("{text}: {s}");
        source = s.source();
    }
    readable(&text)
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
