//! twv analysis: everything that runs a model — integrators, Lyapunov spectra, the hand model
//! and audit, control, tuning, sweeps, reports — and the `twv` command line.

pub mod audit;
pub mod cli;
pub mod control;
pub mod hand_model;
pub mod integrate;
pub mod linear;
pub mod lyapunov;
pub mod output;
pub mod plot;
pub mod report;
pub mod sweep;
pub mod tune;
