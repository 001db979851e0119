//! Options that several jobs share: the integrator, a run's length and sampling, and the
//! controller. Each group is written once and reaches its settings through an accessor, so that
//! `t_end` means the same in `simulate`, `ride` and `phase`, and `kp` the same wherever a
//! controller runs.

use std::sync::Arc;

use serde_json::{json, Value};

use super::options::{
    as_bool, as_choice, as_number, as_vector, is_none, number, number_value, sub, Access, Kind, Opt,
};
use crate::control::steer::SteerSettings;
use crate::control::{
    AntiWindup, ControllerSettings, Profile, RunSettings, Setpoint, VelocityLoop, YawLoop,
};
use crate::error::{Error, Result};
use crate::integrate::DopriOptions;
use crate::linear::{PidGains, SteerGains};
use crate::lyapunov::IntegratorChoice;

const INTEGRATORS: &[&str] = &["rk4", "dopri"];

/// The adaptive integrator's options, or an error naming `option` for a fixed-step run.
fn dopri<'a>(option: &str, i: &'a mut IntegratorChoice) -> Result<&'a mut DopriOptions> {
    match i {
        IntegratorChoice::Dopri(o) => Ok(o),
        IntegratorChoice::Rk4 { .. } => Err(Error::input(
            option,
            "applies to the adaptive integrator: give integrator = dopri",
        )),
    }
}

/// A DOPRI option's value in `settings`, or its default when the run is RK4 (what choosing
/// DOPRI would give).
fn dopri_value<S: Clone>(
    access: &Access<S, IntegratorChoice>,
    settings: &S,
    f: fn(&DopriOptions) -> Value,
) -> Value {
    let mut copy = settings.clone();
    match access(&mut copy) {
        Ok(IntegratorChoice::Dopri(o)) => f(o),
        Ok(IntegratorChoice::Rk4 { .. }) => f(&DopriOptions::default()),
        Err(_) => Value::Null,
    }
}

/// `integrator`, `h`, `rtol`, `atol`, `h_min`, `h_max` (and with `tangent` DOPRI's
/// `tangent_error_control`) of the integrator `access` reaches.
pub fn integrator<S: Clone + 'static>(
    access: Access<S, IntegratorChoice>,
    tangent: bool,
) -> Vec<Opt<S>> {
    let a = access.clone();
    let g = access.clone();
    let mut opts = vec![Opt::new(
        "integrator",
        Kind::Choice,
        "",
        "rk4: fixed-step classical Runge–Kutta (the study's); dopri: adaptive Dormand–Prince \
         5(4) with dense output",
        move |s, v| {
            let i = a(s)?;
            match (as_choice("integrator", v, INTEGRATORS)?, &*i) {
                ("rk4", IntegratorChoice::Rk4 { .. }) | ("dopri", IntegratorChoice::Dopri(_)) => {}
                ("rk4", _) => *i = IntegratorChoice::default(),
                _ => *i = IntegratorChoice::Dopri(DopriOptions::default()),
            }
            Ok(())
        },
        move |s| {
            let mut c = s.clone();
            match g(&mut c) {
                Ok(IntegratorChoice::Rk4 { .. }) => json!("rk4"),
                Ok(IntegratorChoice::Dopri(_)) => json!("dopri"),
                Err(_) => Value::Null,
            }
        },
    )
    .choices(INTEGRATORS)];
    let (a, g) = (access.clone(), access.clone());
    opts.push(Opt::new(
        "h",
        Kind::Number,
        "s",
        "RK4 step (at most the sample interval), or DOPRI's first step (none: chosen from the \
         problem)",
        move |s, v| {
            match a(s)? {
                IntegratorChoice::Rk4 { h } => *h = as_number("h", v)?,
                IntegratorChoice::Dopri(o) => {
                    o.h_init = if is_none(v) {
                        None
                    } else {
                        Some(as_number("h", v)?)
                    }
                }
            }
            Ok(())
        },
        move |s| {
            let mut c = s.clone();
            match g(&mut c) {
                Ok(IntegratorChoice::Rk4 { h }) => json!(*h),
                Ok(IntegratorChoice::Dopri(o)) => json!(o.h_init),
                Err(_) => Value::Null,
            }
        },
    ));
    type DopriField = (
        &'static str,
        &'static str,
        fn(&mut DopriOptions) -> &mut f64,
        fn(&DopriOptions) -> Value,
    );
    let fields: [DopriField; 4] = [
        (
            "rtol",
            "DOPRI relative tolerance",
            |o| &mut o.rtol,
            |o| json!(o.rtol),
        ),
        (
            "atol",
            "DOPRI absolute tolerance",
            |o| &mut o.atol,
            |o| json!(o.atol),
        ),
        (
            "h_min",
            "DOPRI's smallest step [s]: a run that needs a smaller one fails (also bounds the \
             work a run may take)",
            |o| &mut o.h_min,
            |o| json!(o.h_min),
        ),
        (
            "h_max",
            "DOPRI's largest step [s] (inf: no limit)",
            |o| &mut o.h_max,
            |o| number_value(o.h_max),
        ),
    ];
    for (name, help, f, show) in fields {
        let (a, g) = (access.clone(), access.clone());
        opts.push(Opt::new(
            name,
            Kind::Number,
            if name.starts_with('h') { "s" } else { "" },
            help,
            move |s, v| {
                let x = as_number(name, v)?;
                *f(dopri(name, a(s)?)?) = x;
                Ok(())
            },
            move |s| dopri_value(&g, s, show),
        ));
    }
    if tangent {
        let (a, g) = (access.clone(), access);
        opts.push(Opt::new(
            "tangent_error_control",
            Kind::Flag,
            "",
            "Include the tangent vectors in DOPRI's error control",
            move |s, v| {
                let on = as_bool("tangent_error_control", v)?;
                dopri("tangent_error_control", a(s)?)?.tangent_error_control = on;
                Ok(())
            },
            move |s| dopri_value(&g, s, |o| json!(o.tangent_error_control)),
        ));
    }
    opts
}

/// `t_end`, `sample`, the integrator's options and `fall_angle` of the run `access` reaches.
pub fn run<S: Clone + 'static>(access: Access<S, RunSettings>) -> Vec<Opt<S>> {
    let mut opts = vec![
        number(
            "t_end",
            "s",
            "Simulated time",
            sub(access.clone(), |r| &mut r.t_end),
        ),
        number(
            "sample",
            "s",
            "Output sample interval of the CSV and figures",
            sub(access.clone(), |r| &mut r.sample),
        ),
    ];
    opts.extend(integrator(
        sub(access.clone(), |r| &mut r.integrator),
        false,
    ));
    let fall = sub(access, |r| &mut r.fall_angle);
    let g = fall.clone();
    opts.push(Opt::new(
        "fall_angle",
        Kind::Number,
        "rad",
        "Stop the run when |Φ| (the watched state) exceeds this angle: it fell over; inf runs on",
        move |s, v| {
            let a = if is_none(v) {
                None
            } else {
                Some(as_number("fall_angle", v)?).filter(|a| *a != f64::INFINITY)
            };
            *fall(s)? = a;
            Ok(())
        },
        move |s| {
            let mut c = s.clone();
            match g(&mut c) {
                Ok(Some(a)) => json!(*a),
                Ok(None) => json!("inf"),
                Err(_) => Value::Null,
            }
        },
    ));
    opts
}

/// Whether an option creates a closed loop where there is none (the gains do; the rest need one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Need {
    /// The gains: they make a closed loop of an open-loop run.
    Gains,
    /// Any other controller option: it needs a closed loop.
    Loop,
}

/// How a job's controllers are reached: `each(settings, need, f)` calls `f` on every
/// controller the option applies to (one for most jobs, one per portrait for `phase`).
pub type Controllers<S> = Arc<
    dyn Fn(&mut S, Need, &mut dyn FnMut(&mut ControllerSettings) -> Result<()>) -> Result<()>
        + Send
        + Sync,
>;

/// The one controller of a closed-loop job.
pub fn one<S: 'static>(f: fn(&mut S) -> &mut ControllerSettings) -> Controllers<S> {
    Arc::new(move |s, _, apply| apply(f(s)))
}

/// The optional controller of a job that runs open loop unless gains are given.
pub fn optional<S: 'static>(f: fn(&mut S) -> &mut Option<ControllerSettings>) -> Controllers<S> {
    Arc::new(move |s, need, apply| match (f(s), need) {
        (Some(c), _) => apply(c),
        (slot @ None, Need::Gains) => apply(slot.insert(ControllerSettings::default())),
        (None, Need::Loop) => Err(Error::input(
            "gains",
            "controller options need the closed loop: give the gains (kp, kd, …) too",
        )),
    })
}

/// A controller option: `set` on every controller, `get` from the first one.
// Name, kind, unit, help, need, setter and getter: each call reads as one option's entry.
#[allow(clippy::too_many_arguments)]
fn controller_opt<S: Clone + 'static>(
    each: &Controllers<S>,
    name: &'static str,
    kind: Kind,
    unit: &'static str,
    help: &'static str,
    need: Need,
    set: fn(&mut ControllerSettings, &Value) -> Result<()>,
    get: fn(&ControllerSettings) -> Value,
) -> Opt<S> {
    let (e, g) = (each.clone(), each.clone());
    Opt::new(
        name,
        kind,
        unit,
        help,
        move |s, v| e(s, need, &mut |c| set(c, v)),
        move |s| {
            let mut copy = s.clone();
            let mut out = Value::Null;
            let _ = g(&mut copy, Need::Loop, &mut |c| {
                out = get(c);
                Err(Error::Interrupted)
            });
            out
        },
    )
}

/// Named gains from a JSON object (`{"kp": …, "kd": …}`, the others unchanged) or the command
/// line's `Kp,Ki,Kd`; a list is refused, since its order would be a guess.
pub fn gains_value(name: &str, v: &Value, current: PidGains) -> Result<PidGains> {
    match v {
        Value::Object(map) => {
            let mut g = current;
            for (k, x) in map {
                let slot = match k.as_str() {
                    "kp" => &mut g.kp,
                    "ki" => &mut g.ki,
                    "kd" => &mut g.kd,
                    other => {
                        return Err(Error::input(
                            name,
                            format!("`{other}` is not a gain; the gains are kp, ki, kd"),
                        ))
                    }
                };
                *slot = as_number(&format!("{name}.{k}"), x)?;
            }
            Ok(g)
        }
        Value::String(text) if text.contains('=') => {
            let named = super::options::as_named(name, v)?;
            let object = named.into_iter().map(|(k, x)| (k, json!(x))).collect();
            gains_value(name, &Value::Object(object), current)
        }
        Value::String(text) => {
            let v = as_vector(name, v)?;
            let [kp, ki, kd] = v[..] else {
                return Err(Error::input(
                    name,
                    format!("wants three numbers Kp,Ki,Kd, got `{text}`"),
                ));
            };
            Ok(PidGains { kp, ki, kd })
        }
        Value::Array(_) => Err(Error::input(
            name,
            "named gains, {kp, ki, kd}, not a list: the order of a list would be a guess",
        )),
        _ => Err(Error::input(
            name,
            "wants named gains {kp, ki, kd} (or Kp,Ki,Kd as text)",
        )),
    }
}

/// Named steer gains from a JSON object (`{"k_phi": …}`, the others unchanged) or the text
/// `k_phi=…,k_phi_dot=…`; a list is refused, since its order would be a guess.
pub fn steer_gains_value(name: &str, v: &Value, current: SteerGains) -> Result<SteerGains> {
    let named = match v {
        Value::Object(_) | Value::String(_) => super::options::as_named(name, v)?,
        _ => {
            return Err(Error::input(
                name,
                "named gains k_phi=…,k_delta=…,k_phi_dot=…,k_delta_dot=…, not a list: the \
                 order of a list would be a guess",
            ))
        }
    };
    let mut row = current.row();
    for (k, x) in named {
        let i = SteerGains::NAMES
            .iter()
            .position(|n| *n == k)
            .ok_or_else(|| {
                Error::input(
                    name,
                    format!(
                        "`{k}` is not a steer gain; the gains are {}",
                        SteerGains::NAMES.join(", ")
                    ),
                )
            })?;
        row[i] = x;
    }
    Ok(SteerGains::from_row(row))
}

/// Steer gains as an object.
pub fn steer_gains_json(g: &SteerGains) -> Value {
    json!({"k_phi": g.k_phi, "k_delta": g.k_delta, "k_phi_dot": g.k_phi_dot,
           "k_delta_dot": g.k_delta_dot})
}

/// `steer_gains`, `steer_saturation` and `steer_filter`: a steer-torque law on an optional
/// field (the gains turn it on; the limit and the filter refine it).
pub fn steer<S: Clone + 'static>(access: fn(&mut S) -> &mut Option<SteerSettings>) -> Vec<Opt<S>> {
    vec![
        Opt::new(
            "steer_gains",
            Kind::Text,
            "N m/rad, N m s/rad",
            "Steer a two-wheeler with a steer input (whipple): T_delta = k_phi φ + k_delta δ + \
             k_phi_dot φ̇ + k_delta_dot δ̇, named k_phi=…,k_delta=…,k_phi_dot=…,k_delta_dot=… \
             (none: not steered)",
            move |s: &mut S, v| {
                if is_none(v) {
                    *access(s) = None;
                    return Ok(());
                }
                let law = access(s).get_or_insert_with(SteerSettings::default);
                law.gains = steer_gains_value("steer_gains", v, law.gains)?;
                Ok(())
            },
            move |s| {
                let mut copy = s.clone();
                access(&mut copy)
                    .as_ref()
                    .map_or(Value::Null, |l| steer_gains_json(&l.gains))
            },
        ),
        steer_number(
            access,
            "steer_saturation",
            "N m",
            "Steer-torque limit |T_delta| ≤ T_max (none: unlimited); needs steer_gains",
            |l| &mut l.saturation,
        ),
        steer_number(
            access,
            "steer_filter",
            "s",
            "Time constant τ of a first-order filter on the lean and steer rates the steer law \
             reads, 1/(τs + 1) (none: read directly); needs steer_gains",
            |l| &mut l.rate_filter,
        ),
    ]
}

/// What a steer law's rate filter is, for every job that offers one.
pub const RATE_FILTER_HELP: &str = "Time constant τ of a first-order filter on the lean and \
     steer rates the steer law reads, 1/(τs + 1) (none: read directly)";

/// `rate_filter`: the optional τ [s] of a job's steer law, at `at`.
pub fn rate_filter<S: Clone + 'static>(at: fn(&mut S) -> &mut Option<f64>) -> Opt<S> {
    super::options::optional_number(
        "rate_filter",
        "s",
        RATE_FILTER_HELP,
        super::options::field(at),
    )
}

/// An optional number of the steer law (`name`, the law's field `of`), refused without the
/// law's gains.
fn steer_number<S: Clone + 'static>(
    access: fn(&mut S) -> &mut Option<SteerSettings>,
    name: &'static str,
    unit: &'static str,
    help: &'static str,
    of: fn(&mut SteerSettings) -> &mut Option<f64>,
) -> Opt<S> {
    Opt::new(
        name,
        Kind::Number,
        unit,
        help,
        move |s: &mut S, v| {
            let value = if is_none(v) {
                None
            } else {
                Some(as_number(name, v)?)
            };
            match access(s) {
                Some(law) => *of(law) = value,
                None if value.is_none() => {}
                None => {
                    return Err(Error::input(
                        name,
                        "refines the law of steer_gains: give the gains too",
                    ))
                }
            }
            Ok(())
        },
        move |s| {
            let mut copy = s.clone();
            access(&mut copy)
                .as_mut()
                .and_then(|l| *of(l))
                .map_or(Value::Null, |t| json!(t))
        },
    )
}

/// The gains as an object.
pub fn gains_json(g: &PidGains) -> Value {
    json!({"kp": g.kp, "ki": g.ki, "kd": g.kd})
}

/// How a job's gains are reached: `each(settings, f)` calls `f` on every gain set the option
/// applies to.
/// `Need` says whether the gains may be created where there are none (setting them makes an
/// open-loop run a closed loop; reading them shows none).
pub type GainsAccess<S> = Arc<
    dyn Fn(&mut S, Need, &mut dyn FnMut(&mut PidGains) -> Result<()>) -> Result<()> + Send + Sync,
>;

/// The gains of a plain `PidGains` field.
pub fn gains_field<S: 'static>(f: fn(&mut S) -> &mut PidGains) -> GainsAccess<S> {
    Arc::new(move |s, _, apply| apply(f(s)))
}

/// `gains` (named, or Kp,Ki,Kd as text) and `kp`, `ki`, `kd` of the gains `each` reaches.
pub fn gains<S: Clone + 'static>(each: GainsAccess<S>) -> Vec<Opt<S>> {
    let (e, g) = (each.clone(), each.clone());
    let mut opts = vec![Opt::new(
        "gains",
        Kind::Text,
        "N/rad, N/(rad s), N s/rad",
        "PID gains of F = Kp e + Ki ∫e + Kd Φ̇: named, kp=…,ki=…,kd=… (or {kp, ki, kd}; the \
         others keep their values), or Kp,Ki,Kd in that order",
        move |s, v| {
            e(s, Need::Gains, &mut |gains| {
                *gains = gains_value("gains", v, *gains)?;
                Ok(())
            })
        },
        move |s| first_gains(&g, s, gains_json),
    )];
    type Gain = (
        &'static str,
        &'static str,
        &'static str,
        fn(&mut PidGains) -> &mut f64,
    );
    let parts: [Gain; 3] = [
        ("kp", "N/rad", "Proportional gain Kp", |g| &mut g.kp),
        ("ki", "N/(rad s)", "Integral gain Ki (0: a PD law)", |g| {
            &mut g.ki
        }),
        (
            "kd",
            "N s/rad",
            "Derivative gain Kd, on the measured pitch rate",
            |g| &mut g.kd,
        ),
    ];
    for (name, unit, help, f) in parts {
        let (e, g) = (each.clone(), each.clone());
        opts.push(Opt::new(
            name,
            Kind::Number,
            unit,
            help,
            move |s, v| {
                let x = as_number(name, v)?;
                e(s, Need::Gains, &mut |gains| {
                    *f(gains) = x;
                    Ok(())
                })
            },
            move |s| first_gains(&g, s, |gains| json!(*f(&mut gains.clone()))),
        ));
    }
    opts
}

/// `show` of the first gain set `each` reaches in a copy of `settings`.
fn first_gains<S: Clone>(
    each: &GainsAccess<S>,
    settings: &S,
    show: impl Fn(&PidGains) -> Value,
) -> Value {
    let mut copy = settings.clone();
    let mut out = Value::Null;
    let _ = each(&mut copy, Need::Loop, &mut |g| {
        out = show(g);
        Err(Error::Interrupted)
    });
    out
}

const ANTI_WINDUP: &[&str] = &["none", "conditional", "back_calc"];

fn needs_velocity_loop(option: &str) -> Error {
    Error::input(
        option,
        "needs the velocity loop: give v_loop = KP,KI (its gains) too",
    )
}

/// The pitch loop's gains (`gains`, `kp`, `ki`, `kd`; with `with_gains`) and every other
/// controller option of the controllers `each` reaches.
pub fn controller<S: Clone + 'static>(each: Controllers<S>, with_gains: bool) -> Vec<Opt<S>> {
    let mut opts = Vec::new();
    if with_gains {
        let e = each.clone();
        opts.extend(gains(Arc::new(move |s: &mut S, need, f| {
            e(s, need, &mut |c| f(&mut c.pitch.gains))
        })));
    }
    opts.push(controller_opt(
        &each,
        "setpoint",
        Kind::Text,
        "rad",
        "Pitch setpoint Φ_ref: study (0.03·sin Φ, the study's), zero, sine:A (A·sin Φ) or a \
         constant angle",
        Need::Loop,
        |c, v| {
            c.pitch.setpoint = Setpoint::from_value(v)?;
            Ok(())
        },
        |c| json!(c.pitch.setpoint.to_string()),
    ));
    opts.push(controller_opt(
        &each,
        "rate_filter",
        Kind::Number,
        "s",
        "Time constant of a first-order filter on the measured pitch rate (none: no filter)",
        Need::Loop,
        |c, v| {
            c.pitch.derivative_filter = maybe_number("rate_filter", v)?;
            Ok(())
        },
        |c| json!(c.pitch.derivative_filter),
    ));
    opts.push(controller_opt(
        &each,
        "f_max",
        Kind::Number,
        "N",
        "Force limit |F| ≤ F_max (for segway7 the total wheel torque is F·R; none: no limit)",
        Need::Loop,
        |c, v| {
            c.pitch.saturation = maybe_number("f_max", v)?;
            Ok(())
        },
        |c| json!(c.pitch.saturation),
    ));
    opts.push(
        controller_opt(
            &each,
            "anti_windup",
            Kind::Choice,
            "",
            "Anti-windup when saturated: none, conditional (clamping) or back_calc \
             (back-calculation with tracking_time)",
            Need::Loop,
            |c, v| {
                let aw = &mut c.pitch.anti_windup;
                *aw = match (as_choice("anti_windup", v, ANTI_WINDUP)?, *aw) {
                    ("back_calc", AntiWindup::BackCalculation { tracking_time }) => {
                        AntiWindup::BackCalculation { tracking_time }
                    }
                    ("back_calc", _) => AntiWindup::back_calculation(),
                    ("none", _) => AntiWindup::None,
                    _ => AntiWindup::Conditional,
                };
                Ok(())
            },
            |c| {
                json!(match c.pitch.anti_windup {
                    AntiWindup::None => "none",
                    AntiWindup::Conditional => "conditional",
                    AntiWindup::BackCalculation { .. } => "back_calc",
                })
            },
        )
        .choices(ANTI_WINDUP)
        .aliases(&[]),
    );
    opts.push(controller_opt(
        &each,
        "tracking_time",
        Kind::Number,
        "s",
        "Back-calculation tracking time (with anti_windup = back_calc)",
        Need::Loop,
        |c, v| match &mut c.pitch.anti_windup {
            AntiWindup::BackCalculation { tracking_time } => {
                *tracking_time = as_number("tracking_time", v)?;
                Ok(())
            }
            _ => Err(Error::input(
                "tracking_time",
                "needs anti_windup = back_calc",
            )),
        },
        |c| match c.pitch.anti_windup {
            AntiWindup::BackCalculation { tracking_time } => json!(tracking_time),
            _ => match AntiWindup::back_calculation() {
                AntiWindup::BackCalculation { tracking_time } => json!(tracking_time),
                _ => Value::Null,
            },
        },
    ));
    opts.push(controller_opt(
        &each,
        "v_loop",
        Kind::Text,
        "rad per m/s, rad per m",
        "Forward-velocity outer loop gains KP,KI (or {kp, ki}): leans the pitch setpoint by \
         KP·(v_ref − v_x) + KI·∫(v_ref − v_x) dt (none: no velocity loop)",
        Need::Loop,
        |c, v| {
            if is_none(v) {
                c.velocity = None;
                return Ok(());
            }
            let (kp, ki) = match v {
                Value::Object(m) => {
                    let get = |k: &str| m.get(k).map_or(Ok(0.0), |x| as_number("v_loop", x));
                    (get("kp")?, get("ki")?)
                }
                _ => {
                    let g = as_vector("v_loop", v)?;
                    let [kp, ki] = g[..] else {
                        return Err(Error::input(
                            "v_loop",
                            "wants two numbers KP,KI (or {kp, ki})",
                        ));
                    };
                    (kp, ki)
                }
            };
            match &mut c.velocity {
                Some(l) => (l.kp, l.ki) = (kp, ki),
                slot @ None => {
                    *slot = Some(VelocityLoop {
                        kp,
                        ki,
                        reference: Profile::zero(),
                        lean_max: None,
                    })
                }
            }
            Ok(())
        },
        |c| {
            c.velocity
                .as_ref()
                .map_or(Value::Null, |l| json!({"kp": l.kp, "ki": l.ki}))
        },
    ));
    opts.push(controller_opt(
        &each,
        "v_ref",
        Kind::Number,
        "m/s",
        "Constant forward-velocity reference of the velocity loop",
        Need::Loop,
        |c, v| {
            let x = as_number("v_ref", v)?;
            c.velocity
                .as_mut()
                .ok_or_else(|| needs_velocity_loop("v_ref"))?
                .reference = Profile::constant(x);
            Ok(())
        },
        |c| {
            c.velocity
                .as_ref()
                .map_or(json!(0.0), |l| json!(l.reference.value(0.0)))
        },
    ));
    opts.push(controller_opt(
        &each,
        "lean_max",
        Kind::Number,
        "rad",
        "Largest lean the velocity loop may ask for (its integral holds while limited; none: no \
         limit)",
        Need::Loop,
        |c, v| {
            let x = maybe_number("lean_max", v)?;
            c.velocity
                .as_mut()
                .ok_or_else(|| needs_velocity_loop("lean_max"))?
                .lean_max = x;
            Ok(())
        },
        |c| json!(c.velocity.as_ref().and_then(|l| l.lean_max)),
    ));
    opts.push(controller_opt(
        &each,
        "yaw_kp",
        Kind::Number,
        "N m per rad/s",
        "Yaw-rate loop gain: T = KP·(r_ref − w_z) on T2 (differential wheel torque for segway7; \
         none: no yaw loop)",
        Need::Loop,
        |c, v| {
            match (maybe_number("yaw_kp", v)?, &mut c.yaw) {
                (None, y) => *y = None,
                (Some(kp), Some(y)) => y.kp = kp,
                (Some(kp), y @ None) => {
                    *y = Some(YawLoop {
                        kp,
                        reference: Profile::zero(),
                    })
                }
            }
            Ok(())
        },
        |c| json!(c.yaw.as_ref().map(|y| y.kp)),
    ));
    opts.push(controller_opt(
        &each,
        "yaw_ref",
        Kind::Number,
        "rad/s",
        "Constant yaw-rate reference of the yaw loop",
        Need::Loop,
        |c, v| {
            let x = as_number("yaw_ref", v)?;
            c.yaw
                .as_mut()
                .ok_or_else(|| Error::input("yaw_ref", "needs the yaw loop: give yaw_kp too"))?
                .reference = Profile::constant(x);
            Ok(())
        },
        |c| {
            c.yaw
                .as_ref()
                .map_or(json!(0.0), |y| json!(y.reference.value(0.0)))
        },
    ));
    opts
}

/// A number or none.
fn maybe_number(name: &str, v: &Value) -> Result<Option<f64>> {
    if is_none(v) {
        Ok(None)
    } else {
        as_number(name, v).map(Some)
    }
}
