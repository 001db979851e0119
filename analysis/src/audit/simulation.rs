//! Energy checks that need a simulation: with u = 0 the energy T + V stays constant over 20 s;
//! with a constant input its change equals the work the input does, ∫ Qᵀp dt.

use twv_model::Mechanical;

use super::physics::PhysicsCheck;
use super::sampling::Sample;
use crate::integrate::{Dopri5, DopriOptions, IntegrateError, OpenLoop, Stepper};

/// Tight tolerances: the check must measure the model, not the integrator. A budget of 2·10⁶
/// steps (a 20 s run of a vehicle takes ~10⁴): a model stiff enough to need more fails the
/// check with that reason instead of running for hours.
fn tight() -> DopriOptions {
    DopriOptions {
        rtol: 1e-12,
        atol: 1e-12,
        max_steps: 2_000_000,
        ..DopriOptions::default()
    }
}

fn power<const NX: usize, const NU: usize, const NS: usize, M>(
    model: &M,
    x: &[f64; NX],
    u: &[f64; NU],
) -> f64
where
    M: Mechanical<NX, NU, NS>,
{
    let mut q = [0.0; NS];
    model.input_forces(x, u, &mut q);
    q.iter().zip(&x[NX - NS..]).map(|(a, b)| a * b).sum()
}

/// Simulate from `s` for `t_end` seconds; return the energy change and the input work
/// (composite Simpson on a grid the integrator lands on exactly).
fn energy_and_work<const NX: usize, const NU: usize, const NS: usize, M>(
    model: &M,
    s: &Sample<NX, NU>,
    t_end: f64,
) -> Result<(f64, f64, f64), IntegrateError>
where
    M: Mechanical<NX, NU, NS>,
{
    let field = OpenLoop::new(model, s.u);
    let mut stepper = Dopri5::<_, NX, 0>::new(&field, 0.0, s.x, [], tight(), false)?;
    let intervals = (t_end / 1e-3).ceil() as usize * 2;
    let dt = t_end / intervals as f64;
    let mut work = power(model, &s.x, &s.u);
    for i in 1..=intervals {
        stepper.advance_to(i as f64 * dt)?;
        let p = power(model, &stepper.state().x, &s.u);
        let weight = if i == intervals {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        work += weight * p;
    }
    work *= dt / 3.0;
    let (e0, e1) = (model.energy(&s.x), model.energy(&stepper.state().x));
    Ok((e1 - e0, work, e0.abs().max(e1.abs())))
}

/// Energy drift over 20 s with u = 0, and energy change vs input work over 2 s with the
/// samples' constant inputs; a blow-up is reported as a failed check naming it.
pub fn energy_checks<const NX: usize, const NU: usize, const NS: usize, M>(
    model: &M,
    samples: &[Sample<NX, NU>],
    count: usize,
) -> [PhysicsCheck; 2]
where
    M: Mechanical<NX, NU, NS>,
{
    let chosen: Vec<&Sample<NX, NU>> = samples.iter().skip(2).take(count).collect();
    let run = |free: bool| -> Result<f64, IntegrateError> {
        let mut worst: f64 = 0.0;
        for s in &chosen {
            let s = if free {
                Sample {
                    x: s.x,
                    u: [0.0; NU],
                }
            } else {
                **s
            };
            let (change, work, scale) = energy_and_work(model, &s, if free { 20.0 } else { 2.0 })?;
            worst = worst.max((change - work).abs() / scale.max(work.abs()).max(1.0));
        }
        Ok(worst)
    };
    let check = |name: &'static str, free: bool, detail: &str| match run(free) {
        Ok(err) => PhysicsCheck::new(
            name,
            err,
            1e-8,
            format!("{detail}, {} states, DOPRI5 rtol 1e-12", chosen.len()),
        ),
        Err(e) => PhysicsCheck::new(name, f64::INFINITY, 1e-8, format!("simulation failed: {e}")),
    };
    [
        check("energy drift, u = 0, 20 s", true, "|ΔE| / |E|"),
        check("ΔE = input work, 2 s", false, "|ΔE − ∫Qᵀp dt| / |E|"),
    ]
}
