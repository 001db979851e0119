//! twv analysis: everything that runs a model — integrators, Lyapunov spectra, the hand model
//! and audit, control, tuning, sweeps, reports — behind one typed API ([`api`]) that the `twv`
//! command line (crate `twv-cli`), the Python package and the live page call.
//!
//! ```no_run
//! use twv_analysis::api::{spectrum, SpectrumSettings};
//! use twv_analysis::lyapunov::LyapunovSettings;
//! use twv_analysis::model::ModelSpec;
//!
//! let model = ModelSpec::shipped("vehicle8").resolve()?;
//! let result = spectrum(
//!     &model,
//!     &SpectrumSettings {
//!         x0: vec![0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
//!         lyapunov: LyapunovSettings::preset_paper(),
//!         ..SpectrumSettings::default()
//!     },
//!     &twv_analysis::api::Silent,
//! )?;
//! println!("{}", result.result.classification);
//! # Ok::<(), twv_analysis::Error>(())
//! ```

pub mod api;
pub mod audit;
pub mod control;
pub mod error;
pub mod export;
pub mod hand_file;
pub mod hand_model;
pub mod integrate;
pub mod jobs;
pub mod linear;
pub mod lyapunov;
pub mod machine;
pub mod model;
pub mod output;
pub mod plot;
pub mod progress;
pub mod report;
pub mod sweep;
pub mod tune;

pub use error::{Error, Result};
