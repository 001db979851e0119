//! Gain tuning of the pitch loop to a margin specification (`twv tune --spec "dpm>=45"`):
//! Clarabel subproblems in a convex–concave procedure (Hast, Åström, Bernhardsson & Boyd,
//! ECC 2013), verified independently by the linear analysis.

pub mod ccp;
pub mod certificate;
mod qp;
pub mod spec;
pub mod steer;
pub mod tuner;

pub use ccp::Objective;
pub use certificate::{certify, Certificate};
pub use spec::{Requirement, Spec, SpecError};
pub use steer::{certify_steer, tune_steer, SteerCertificate, SteerTune, SteerTuneOptions};
pub use tuner::{tune, tune_with, validate, TuneError, TuneOptions, TuneResult, TuneStatus};
