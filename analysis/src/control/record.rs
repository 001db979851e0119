//! One closed-loop run with what the controller did at every sample and the metrics.

use twv_model::Model;

use super::error::ControlError;
use super::field::{Command, PidLoop};
use super::metrics::{response_metrics, LoopMetrics};
use super::simulate::{simulate, RunSettings, Trajectory};
use crate::progress::Progress;

/// A closed-loop run: the augmented trajectory, the commands at the samples, the metrics.
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedLoopRun<const NA: usize, const NU: usize> {
    /// Samples of the augmented state (model states, then controller states).
    pub trajectory: Trajectory<NA>,
    /// The controller's command at each sample.
    pub commands: Vec<Command<NU>>,
    /// Metrics of the run.
    pub metrics: LoopMetrics,
}

/// Runs `field` from the model state `x0` (controller states from
/// [`PidLoop::initial_state`]) and measures it.
pub fn run_closed_loop<M, const NX: usize, const NU: usize, const NA: usize>(
    field: &PidLoop<'_, M, NX, NU, NA>,
    x0: &[f64; NX],
    run: &RunSettings,
    progress: &dyn Progress,
) -> Result<ClosedLoopRun<NA, NU>, ControlError>
where
    M: Model<NX, NU>,
{
    let xa0 = field.initial_state(x0);
    let trajectory = simulate(field, &xa0, field.plant().measured.phi, run, progress)?;
    let commands: Vec<Command<NU>> = trajectory
        .t
        .iter()
        .zip(&trajectory.x)
        .map(|(t, x)| field.command(*t, x))
        .collect();
    let metrics = loop_metrics(field, &trajectory, &commands);
    Ok(ClosedLoopRun {
        trajectory,
        commands,
        metrics,
    })
}

/// The metrics of a recorded run.
pub fn loop_metrics<M, const NX: usize, const NU: usize, const NA: usize>(
    field: &PidLoop<'_, M, NX, NU, NA>,
    traj: &Trajectory<NA>,
    commands: &[Command<NU>],
) -> LoopMetrics
where
    M: Model<NX, NU>,
{
    let info = field.model().info();
    let index = |name: &str| info.states.iter().position(|s| *s == name);
    let first = &traj.x[0];
    let last = traj.last();
    let at_end = |name: &str| index(name).map(|i| last[i]);
    let phi_i = field.plant().measured.phi;
    let target = field.settings().pitch.setpoint.rest_value();
    let phi = response_metrics(&traj.t, &traj.component(phi_i), target, 0.02);
    let max_abs =
        |f: fn(&Command<NU>) -> f64| commands.iter().fold(0.0_f64, |m, c| m.max(f(c).abs()));
    let saturated = commands.iter().filter(|c| c.saturated).count();
    let (ix, iy) = (index("x"), index("y"));
    let drift_distance = ix.map(|ix| {
        let dy = iy.map_or(0.0, |iy| last[iy] - first[iy]);
        (last[ix] - first[ix]).hypot(dy)
    });
    LoopMetrics {
        phi,
        peak_force: max_abs(|c| c.force),
        peak_force_command: max_abs(|c| c.force_cmd),
        saturated_fraction: saturated as f64 / commands.len().max(1) as f64,
        final_phi: last[phi_i],
        final_v_x: at_end("v_x"),
        final_v_y: at_end("v_y"),
        final_w_z: at_end("w_z"),
        final_theta: at_end("theta"),
        drift_distance,
        x_displacement: ix.map(|ix| last[ix] - first[ix]),
    }
}
