//! Linear analysis of a twv model: linearisation at an equilibrium from the generated
//! Jacobians, eigenvalues with named (drift) modes, the study's PID pitch loop (closed-loop
//! matrix, Routh–Hurwitz reference), gain/phase/delay/disk margins, and LQR through a Riccati
//! solver written here. Everything works on matrices, so it serves any model size.

pub mod care;
pub mod cart_pendulum;
pub mod disk;
pub mod error;
pub mod freq;
pub mod linearize;
pub mod lqr;
pub mod lyap;
pub mod margins;
pub mod modes;
pub mod pitch;
pub mod report;
pub mod siso;
pub mod steer;

pub use care::{solve_care, CareSolution, CareStatus};
pub use cart_pendulum::CartPendulum;
pub use disk::{Disk, DiskMargin};
pub use error::LinearError;
pub use linearize::{linearize, state_index, Linearization, OperatingPoint};
pub use lqr::{lqr, Lqr};
pub use margins::{loop_margins, GridOptions, Margins};
pub use modes::{eigenvalues, modes, spectral_abscissa, Mode, ModeKind};
pub use pitch::{ClosedLoop, GainBasis, LoopOptions, PidGains, PitchLoop};
pub use report::{analyse_pitch, loop_response, ExclusionDisk, LoopResponse, PitchAnalysis};
pub use siso::{HiddenKind, HiddenPart, SisoPlant};
pub use steer::{SteerAnalysis, SteerClosedLoop, SteerGains, SteerLoop};

/// A matrix as JSON in its natural shape: one list per row (nalgebra's own serialisation is
/// its column-major storage, which a reader would take for rows).
pub fn rows<S: serde::Serializer>(m: &nalgebra::DMatrix<f64>, s: S) -> Result<S::Ok, S::Error> {
    use serde::Serialize;
    let rows: Vec<Vec<f64>> = m.row_iter().map(|r| r.iter().copied().collect()).collect();
    rows.serialize(s)
}
