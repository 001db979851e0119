//! twv's errors as Python exceptions: every one a `TwvError` (a `ValueError`), with the message
//! the CLI prints, and a subclass saying what kind of thing was wrong.

use pyo3::create_exception;
use pyo3::exceptions::{PyKeyboardInterrupt, PyValueError};
use pyo3::PyErr;
use twv_analysis::Error;

create_exception!(
    _native,
    TwvError,
    PyValueError,
    "An error of twv: bad input, a model that cannot do the job, or a run that failed."
);
create_exception!(
    _native,
    InputError,
    TwvError,
    "A setting or an input array that is missing, malformed or out of range."
);
create_exception!(
    _native,
    ModelError,
    TwvError,
    "A model IR, parameter set or model that cannot be read or cannot do the job."
);
create_exception!(
    _native,
    NumericalError,
    TwvError,
    "A computation that produced non-finite numbers or could not be integrated."
);

/// The Python exception for a twv error.
pub fn to_py(e: Error) -> PyErr {
    // The whole chain, as the CLI prints it ("invalid Lyapunov settings: h = -1 …").
    let text = twv_analysis::error::one_line(&e);
    match e {
        Error::Interrupted => PyKeyboardInterrupt::new_err(text),
        Error::Input { .. }
        | Error::LyapunovSettings(_)
        | Error::Control(_)
        | Error::Spec(_)
        | Error::Sweep(_)
        | Error::HandFile(_) => InputError::new_err(text),
        Error::Ir(_)
        | Error::Params(_)
        | Error::Model(_)
        | Error::Size(_)
        | Error::UnknownModel { .. }
        | Error::Unsupported { .. }
        | Error::Read { .. } => ModelError::new_err(text),
        Error::NonFinite { .. } | Error::Lyapunov(_) | Error::Integrate(_) => {
            NumericalError::new_err(text)
        }
        _ => TwvError::new_err(text),
    }
}

/// The exception for a panic of Rust code (a bug of twv): its message, never a crash.
pub fn panicked(payload: Box<dyn std::any::Any + Send>) -> PyErr {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    TwvError::new_err(format!("internal error of twv (please report it): {what}"))
}
