//! What the report computes (every section through the typed API) and the page it composes
//! from the results: the summary of findings first, then one section per part of the study.

use serde::Serialize;

use super::findings::{
    audit_check, bicycle_finding, equations_claim, hyperchaos_claim, linear_finding, map_finding,
    open_loop_finding, pd_exponents_claim, recovery_claim, recovery_finding, trace_check,
    tune_finding, Check, Finding,
};
use super::html::{Figure, Page};
use super::{HorizonRow, ReportResults, ReportSettings};
use crate::api::{
    analyse, audit_model, portraits, ride, simulate, spectrum, steady_motion, steer, sweep,
    tune_model_with, LinearSettings, PhaseSettings, Progress, RideResult, RideSettings,
    RideVerdict, SimSettings, SpectrumSettings, SteadyResult, SteadySettings, SteerLoopSettings,
    SteerResult, SweepSettings, TuneSettings, UncertaintyResult, UncertaintySettings, AUDITED,
};
use crate::audit::AuditSettings;
use crate::control::steer::SteerSettings;
use crate::control::{ControllerSettings, RunSettings, STUDY_PD};
use crate::error::{Error, Result};
use crate::lyapunov::{InitialBasis, LyapunovSettings};
use crate::model::{ModelSource, ModelSpec, ParamSource, ResolvedModel};
use crate::plot::{Curve, LineChart};
use crate::sweep::{Grid, Metric, PointResult};

/// Sections computed (the progress steps).
pub const STEPS: usize = 8;

/// The bicycle section's push: a lean rate [rad/s] added to straight running at
/// [`PUSH_SPEED`], below the weave speed, where a bicycle nobody steers falls.
pub const PUSH: f64 = 0.5;
/// The speed of the bicycle section's push [m/s].
pub const PUSH_SPEED: f64 = 3.0;

/// The Whipple benchmark bicycle: self-stable nowhere but between its weave and capsize speeds,
/// balanced by a tuned steer-gain schedule everywhere, and one push below the weave speed,
/// unsteered and steered.
#[derive(Debug, Clone, Serialize)]
pub struct BicycleSection {
    /// Its eigenvalues against speed, nobody steering.
    pub steady: SteadyResult,
    /// The tuned steer schedule, certified and checked on the nonlinear model.
    pub steer: SteerResult,
    /// The push at [`PUSH_SPEED`] nobody steers.
    pub unsteered: RideResult,
    /// The same push, steered by the schedule's gains at that speed.
    pub steered: RideResult,
    /// A measured bicycle drawn within its parameters' uncertainty (Monte Carlo): its weave
    /// and capsize speeds, and a steer design tuned on its nominal values checked at
    /// [`PUSH_SPEED`] on every draw (`None`: no measured bicycle was given).
    pub uncertainty: Option<UncertaintyResult>,
}

/// Draws of the report's Monte Carlo (quick: fewer).
const DRAWS: usize = 200;
const QUICK_DRAWS: usize = 40;

fn bicycle(
    quick: bool,
    measured: Option<&ParamSource>,
    progress: &dyn Progress,
) -> Result<BicycleSection> {
    let bike = ModelSpec::shipped("whipple").resolve()?;
    let steady = steady_motion(
        &bike,
        &SteadySettings {
            step: if quick { 0.1 } else { 0.01 },
            ..SteadySettings::default()
        },
        progress,
    )?;
    let schedule = steer(
        &bike,
        &SteerLoopSettings {
            step: if quick { 1.0 } else { 0.5 },
            ..SteerLoopSettings::default()
        },
        progress,
    )?;
    let gains = schedule
        .points
        .iter()
        .find(|p| p.speed == PUSH_SPEED)
        .and_then(|p| p.gains());
    let push = |steer: Option<SteerSettings>| {
        ride(
            &bike,
            &RideSettings {
                speed: Some(PUSH_SPEED),
                perturb: [("w_phi".to_string(), PUSH)].into(),
                steer,
                run: RunSettings {
                    t_end: 5.0,
                    ..RunSettings::default()
                },
                ..RideSettings::default()
            },
            progress,
        )
    };
    let unsteered = push(None)?;
    let steered = push(Some(SteerSettings::gains(gains.unwrap_or_default())))?;
    let uncertainty = match measured {
        Some(params) => {
            let measured = ModelSpec::shipped("whipple")
                .with_params(params.clone())
                .resolve()?;
            Some(crate::api::uncertainty(
                &measured,
                &UncertaintySettings {
                    samples: if quick { QUICK_DRAWS } else { DRAWS },
                    speed: PUSH_SPEED,
                    ..UncertaintySettings::default()
                },
                progress,
            )?)
        }
        None => None,
    };
    Ok(BicycleSection {
        steady,
        steer: schedule,
        unsteered,
        steered,
        uncertainty,
    })
}

/// The study's initial tilt [rad].
const TILT: f64 = 0.1;

/// The vehicle model `name` with the report's parameters (segway7's own when given).
fn vehicle(settings: &ReportSettings, name: &str) -> Result<ResolvedModel> {
    let params = match (&settings.segway_params, name) {
        (Some(p), "segway7") => p.clone(),
        _ => settings.params.clone(),
    };
    ModelSpec {
        model: ModelSource::Shipped(name.to_string()),
        params,
        ..ModelSpec::default()
    }
    .resolve()
}

/// The translational mass times g of vehicle8, and whether the upright is open-loop unstable
/// (λ² > 0), which is when the prediction "stable iff Kp > M_x g" holds.
fn predicted_boundary(model: &ResolvedModel) -> Option<f64> {
    let p = |n: &str| model.param(n).unwrap_or(f64::NAN);
    let (m1, m2, g, b, iyy) = (p("m1"), p("m2"), p("g"), p("b"), p("I2_yy"));
    let mx = m1 + m2;
    let ip = iyy + m2 * b * b;
    let lam2 = m2 * g * b * mx / (ip * mx - m2 * m2 * b * b);
    (lam2 > 0.0).then_some(mx * g)
}

fn open_loop(x0: &[f64], lyapunov: LyapunovSettings) -> SpectrumSettings {
    SpectrumSettings {
        x0: x0.to_vec(),
        lyapunov,
        ..SpectrumSettings::default()
    }
}

/// The model section's own data: what the IR holds, as the page shows it.
#[derive(Debug, Clone, Serialize)]
pub struct ModelSection {
    /// The IR's description.
    pub description: String,
    /// Its content hash.
    pub hash: String,
    /// Where the parameters came from.
    pub params_origin: String,
    /// (name, value, unit, description) per parameter.
    pub params: Vec<(String, f64, String, String)>,
    /// M, Cp, F, Q as formulas.
    pub terms: String,
}

fn model_section(model: &ResolvedModel) -> ModelSection {
    let ir = &model.ir;
    let speeds: Vec<String> = ir.states()[ir.nx() - ir.ns()..]
        .iter()
        .map(|s| s.name.clone())
        .collect();
    let mut terms = String::from(
        "Poincaré form  M(q) ṗ + C(q,p) p + F(q) = Q(u),  q = (phi, x, y, theta), p = (w_y, v_x, v_y, w_z)\n\n",
    );
    for part in ["M", "Cp", "F", "Q"] {
        if let Some(f) = ir.function(part) {
            let fm = twv_ir::formulas(ir, f, &speeds, &speeds);
            for (name, e) in &fm.temporaries {
                terms += &format!("  {part}: {name} = {e}\n");
            }
            for (label, e) in &fm.entries {
                terms += &format!("{label} = {e}\n");
            }
            terms += "\n";
        }
    }
    ModelSection {
        description: ir.description().to_string(),
        hash: ir.hash().to_string(),
        params_origin: model.params_origin.clone(),
        params: ir
            .params()
            .iter()
            .zip(&model.params)
            .map(|(p, v)| (p.name.clone(), *v, p.unit.clone(), p.description.clone()))
            .collect(),
        terms,
    }
}

/// Everything the report computes.
pub fn compute(settings: &ReportSettings, progress: &dyn Progress) -> Result<ReportResults> {
    let quick = settings.quick;
    let v8 = vehicle(settings, "vehicle8")?;
    let tilt = v8.rest_with("phi", TILT)?;

    let audit_settings = AuditSettings {
        samples: if quick { 30 } else { 200 },
        simulations: if quick { 1 } else { 4 },
        tolerance: settings.audit_tolerance,
        ..AuditSettings::default()
    };
    // Each part hears a Ctrl-C (and a step that cannot, the audit and the linear analysis of
    // a few milliseconds to a second, is followed by a look at it).
    let quiet = &crate::progress::CancelOnly(progress);
    let step = || {
        progress.advance(1);
        if progress.cancelled() {
            Err(crate::error::Error::Interrupted)
        } else {
            Ok(())
        }
    };
    let audit = AUDITED
        .iter()
        .map(|name| {
            if progress.cancelled() {
                return Err(crate::error::Error::Interrupted);
            }
            audit_model(&vehicle(settings, name)?, &audit_settings)
        })
        .collect::<Result<Vec<_>>>()?;
    step()?;

    let preset = spectrum(
        &v8,
        &open_loop(&tilt, LyapunovSettings::preset_paper()),
        quiet,
    )?;
    let iterations: &[usize] = if quick {
        &[100, 1000]
    } else {
        &[100, 1000, 10000]
    };
    let lyapunov_horizons = iterations
        .iter()
        .map(|&k| {
            let base = LyapunovSettings {
                iterations: k,
                record_running: false,
                ..LyapunovSettings::preset_paper()
            };
            let random = LyapunovSettings {
                basis: InitialBasis::Random { seed: 1 },
                ..base.clone()
            };
            Ok(HorizonRow {
                horizon_s: base.horizon(),
                identity: spectrum(&v8, &open_loop(&tilt, base), quiet)?,
                random_seed_1: spectrum(&v8, &open_loop(&tilt, random), quiet)?,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    step()?;

    let phase = portraits(
        &v8,
        &PhaseSettings {
            run: RunSettings {
                t_end: if quick { 5.0 } else { 10.0 },
                ..RunSettings::default()
            },
            ..PhaseSettings::default()
        },
        quiet,
    )?;
    step()?;

    let recovery = [("forward tilt", TILT), ("backward tilt", -TILT)]
        .iter()
        .map(|(name, phi0)| {
            simulate(
                &v8,
                &SimSettings {
                    title: format!("study PD, {name} of {} rad", phi0.abs()),
                    scenario: name.to_string(),
                    controller: ControllerSettings::default(),
                    phi0: *phi0,
                    ..SimSettings::default()
                },
                quiet,
            )
        })
        .collect::<Result<Vec<_>>>()?;
    step()?;

    let linear = analyse(&v8, &LinearSettings::default())?;
    let tune = tune_model_with(&v8, &TuneSettings::default(), quiet)?;
    step()?;

    let n = if quick { 21 } else { 61 };
    let grid = Grid::study_gains(n);
    let map = sweep(
        &v8,
        &SweepSettings::new(grid, Metric::SpectralAbscissa),
        quiet,
    )?;
    step()?;

    let closed = spectrum(
        &v8,
        &SpectrumSettings {
            x0: tilt.clone(),
            controller: Some(ControllerSettings::pid(STUDY_PD)),
            lyapunov: LyapunovSettings {
                transient: 20.0,
                iterations: if quick { 200 } else { 400 },
                ..LyapunovSettings::preset_paper()
            },
            ..SpectrumSettings::default()
        },
        quiet,
    )?;
    step()?;

    let bicycle = bicycle(quick, settings.measured_bicycle.as_ref(), quiet)?;
    step()?;

    let audit_ok = audit_check(&audit);
    let checks: Vec<Check> = vec![audit_ok.clone(), trace_check(&preset)];
    let horizons: Vec<(f64, Vec<f64>)> = lyapunov_horizons
        .iter()
        .map(|h| (h.horizon_s, h.random_seed_1.result.exponents.clone()))
        .collect();
    let findings: Vec<Finding> = [
        open_loop_finding(&preset, &horizons),
        recovery_finding(&recovery[0]),
        recovery_finding(&recovery[1]),
        linear_finding(&linear),
        tune_finding(&tune),
        map_finding(&map, predicted_boundary(&v8)),
        bicycle_finding(&bicycle),
    ]
    .into();
    let longest = lyapunov_horizons
        .last()
        .map_or(&preset, |h| &h.random_seed_1);
    let claims = vec![
        hyperchaos_claim(&preset, longest),
        pd_exponents_claim(&closed),
        recovery_claim(&recovery),
        equations_claim(&audit_ok),
    ];
    Ok(ReportResults {
        passed: checks.iter().all(|c| c.passed),
        model: model_section(&v8),
        checks,
        findings,
        claims,
        audit,
        lyapunov_preset: preset,
        lyapunov_horizons,
        phase,
        recovery,
        linear,
        tune,
        map,
        closed_loop_lyapunov: closed,
        bicycle,
        wall_time_s: 0.0,
        machine: String::new(),
    })
}

fn sci(v: f64) -> String {
    format!("{v:.3e}")
}

/// A figure drawn as SVG and PNG — unless the run was cancelled: drawing the figures is most
/// of a report's time in a release build, so a Ctrl-C is looked at before each one.
fn figure(
    progress: &dyn Progress,
    file: &str,
    figure: crate::plot::Figure,
    caption: &str,
) -> Result<Figure> {
    if progress.cancelled() {
        return Err(Error::Interrupted);
    }
    Ok(Figure {
        file: format!("figures/{file}"),
        svg: figure.svg()?,
        png: figure.png()?,
        caption: caption.to_string(),
    })
}

/// The page and its figures.
pub fn page(
    settings: &ReportSettings,
    r: &ReportResults,
    progress: &dyn Progress,
) -> Result<(String, Vec<Figure>)> {
    let mut page = Page::default();
    let mut figures = Vec::new();
    let mut add = |page: &mut Page, fig: Figure| {
        page.figure(&fig);
        figures.push(fig);
    };
    page.heading(1, "twv report: two-wheeled self-balancing vehicle");
    page.summary(&r.checks, &r.findings);

    // 1. Model and audit.
    page.heading(2, "1. The model");
    page.paragraph(&format!(
        "vehicle8, the study's model: {} Its equations were derived from bodies and joints by the \
         Python/CasADi modeling step (Hamel's equations in the quasi-velocities, like ProPac), \
         exported as the model IR {} and compiled into Rust. Parameters: {}.",
        r.model.description, r.model.hash, r.model.params_origin
    ));
    let rows: Vec<Vec<String>> = r
        .model
        .params
        .iter()
        .map(|(n, v, u, d)| vec![n.clone(), format!("{v}"), u.clone(), d.clone()])
        .collect();
    page.paragraph("Parameter values (SI units); the wheel values enter only segway7.");
    page.table(&["parameter", "value", "unit", "meaning"], &rows);
    if let Some(text) = &settings.params_text {
        page.paragraph(&format!("The parameter file ({}):", r.model.params_origin));
        page.preformatted(text);
    }
    page.paragraph(
        "The derived terms as the IR holds them (structural zeros omitted; t1, t2, … are shared \
         subexpressions):",
    );
    page.preformatted(&r.model.terms);
    page.paragraph(&format!(
        "Audit: the generated code against an independent hand model (Kane's method, closed \
         form), term by term at {} random large-angle, fast-spin states, and physical checks \
         (eigenvalues against the λ² formula, energy conservation and balance, symmetries). \
         Tolerance {:.0e} (normwise relative). {}",
        r.audit.first().map_or(0, |a| a.samples),
        r.audit.first().map_or(0.0, |a| a.tolerance),
        r.checks[0].detail
    ));
    let rows: Vec<Vec<String>> = r
        .audit
        .iter()
        .map(|a| {
            let mut row = vec![a.model.clone()];
            row.extend(a.quantities.iter().map(|q| sci(q.max_rel)));
            let passed = a.physics.iter().filter(|c| c.passed).count();
            row.push(format!("{passed}/{}", a.physics.len()));
            row.push(if a.passed { "passed" } else { "FAILED" }.into());
            row
        })
        .collect();
    page.table(
        &[
            "model",
            "M",
            "Cp",
            "F",
            "Q",
            "f",
            "∂f/∂x",
            "physical checks",
            "verdict",
        ],
        &rows,
    );

    // 2. Open-loop spectrum.
    let preset = &r.lyapunov_preset;
    let res = &preset.result;
    page.heading(2, "2. Open-loop Lyapunov spectrum (the study's Fig. 3)");
    page.paragraph(&format!(
        "The unforced vehicle8 from a {TILT} rad forward tilt, at the study's preset: {} \
         exponents, RK4 with h = 1 ms, re-orthonormalisation every T = 0.1 s, K = 100 intervals. \
         The figure shows the running estimates on a logarithmic time axis.",
        res.exponents.len()
    ));
    add(
        &mut page,
        figure(
            progress,
            "lyapunov_running.svg",
            preset.running_figure(),
            "Running estimates of the exponents (study preset).",
        )?,
    );
    let rows: Vec<Vec<String>> = res
        .exponents
        .iter()
        .zip(&res.stderr)
        .zip(&res.signs)
        .enumerate()
        .map(|(i, ((l, e), d))| {
            vec![
                format!("λ{}", i + 1),
                format!("{l:+.5}"),
                format!("{e:.5}"),
                format!("{:?}", d.sign).to_lowercase(),
                d.test.to_string(),
            ]
        })
        .collect();
    page.table(
        &[
            "exponent",
            "value [1/s]",
            "σ (1 standard error)",
            "sign",
            "test",
        ],
        &rows,
    );
    page.paragraph(&format!(
        "Sign tests: significant beyond {}σ and beyond the floor {:.3e} 1/s. {} Classification: \
         {}.{}",
        res.significance,
        res.zero_floor,
        r.checks[1].detail,
        res.classification,
        match preset.drift_note() {
            n if n.is_empty() => String::new(),
            n => format!(" Note: {n}."),
        }
    ));
    let rows: Vec<Vec<String>> = r
        .lyapunov_horizons
        .iter()
        .map(|h| {
            let pos = |s: &crate::api::SpectrumResult| {
                s.result
                    .signs
                    .iter()
                    .filter(|d| d.sign == crate::lyapunov::ExponentSign::Positive)
                    .count()
            };
            let max_abs = h
                .random_seed_1
                .result
                .exponents
                .iter()
                .fold(0.0_f64, |m, l| m.max(l.abs()));
            vec![
                format!("{:.0} s", h.horizon_s),
                format!("{:+.5}", h.identity.result.exponents[0]),
                format!("{}", pos(&h.random_seed_1)),
                format!("{max_abs:.5}"),
                format!("{:+.3e}", h.random_seed_1.result.sum),
                h.random_seed_1.result.classification.kind().to_string(),
            ]
        })
        .collect();
    page.paragraph(&format!(
        "The same run at longer horizons, from the identity basis and from a random orthonormal \
         basis (seed 1). {}",
        r.findings[0].text
    ));
    page.table(
        &[
            "horizon T·K",
            "λ1 (identity)",
            "significantly positive (random basis)",
            "max |λ| (random)",
            "Σλ (random)",
            "classification (random)",
        ],
        &rows,
    );

    // 3. Phase portraits.
    page.heading(2, "3. Phase trajectories (the study's Fig. 4 a–d)");
    page.paragraph(
        "Closed-loop (Φ, dΦ/dt) trajectories from ±0.1 and ±0.2 rad for four PID gain sets; the \
         study gives only the last (PD, Kp = 3860, Kd = 1980), the first three are chosen to \
         show the regimes it describes: integral gain above the Routh–Hurwitz limit, a stable \
         slow oscillation, Kp below M_x g (a saddle).",
    );
    add(
        &mut page,
        figure(
            progress,
            "phase.svg",
            r.phase.combined_figure(2),
            "Phase portraits (Φ, dΦ/dt) for gain sets (a)–(d).",
        )?,
    );
    let rows: Vec<Vec<String>> = r
        .phase
        .portraits
        .iter()
        .map(|p| {
            let fell = p
                .runs
                .iter()
                .filter(|run| matches!(run.end, crate::control::RunEnd::Fell { .. }))
                .count();
            vec![
                p.label.clone(),
                p.loop_abscissa.map_or("—".into(), |a| format!("{a:+.4}")),
                if p.stable { "stable" } else { "unstable" }.to_string(),
                if fell == 0 {
                    "none fall".into()
                } else {
                    format!("{fell} of {} fall", p.runs.len())
                },
            ]
        })
        .collect();
    page.table(
        &[
            "gain set",
            "largest non-zero Re λ at the upright [1/s]",
            "linearised loop",
            "trajectories",
        ],
        &rows,
    );

    // 4. Tilt recovery.
    page.heading(2, "4. Recovery from a tilt (the study's Figs. 5 and 6)");
    page.paragraph(
        "The study's PD (Kp = 3860, Kd = 1980, setpoint 0.03·sinΦ) after a 0.1 rad forward and \
         backward tilt: Φ, dΦ/dt, forward velocity and displacement against time.",
    );
    let mut rows = Vec::new();
    for sim in &r.recovery {
        let prefix = sim.scenario.replace(' ', "_");
        for (file, fig) in sim.figures() {
            if ["phi.svg", "phi_dot.svg", "v_x.svg", "x.svg"].contains(&file.as_str()) {
                let caption = format!("{}: {}", sim.scenario, file.trim_end_matches(".svg"));
                add(
                    &mut page,
                    figure(progress, &format!("{prefix}_{file}"), fig, &caption)?,
                );
            }
        }
        let m = &sim.metrics;
        let opt = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v:.4}"));
        rows.push(vec![
            sim.scenario.clone(),
            format!("{:?}", sim.recovery).to_lowercase(),
            opt(m.phi.settling_time),
            opt(m.phi.overshoot.map(|o| 100.0 * o)),
            format!("{:.4}", m.phi.iae),
            format!("{:.1}", m.peak_force),
            opt(m.final_v_x),
            opt(m.x_displacement),
        ]);
    }
    page.table(
        &[
            "tilt",
            "verdict",
            "2 % settling [s]",
            "overshoot [%]",
            "IAE [rad s]",
            "peak force [N]",
            "final v_x [m/s]",
            "x at the end [m]",
        ],
        &rows,
    );
    page.paragraph(&format!("{} {}", r.findings[1].text, r.findings[2].text));

    // 5. Linear analysis and tuning.
    page.heading(2, "5. Linear analysis, margins, tuned gains and LQR");
    page.paragraph(&format!(
        "Linearisation at the upright from the generated Jacobians; the pitch loop of the \
         study's PD with its gain, phase, delay and balanced disk margins (Seiler, Packard & \
         Gahinet 2020) when it is stable, and an LQR design on (Φ, x, dΦ/dt, v_x) for \
         comparison. {}",
        r.findings[3].text
    ));
    page.preformatted(&r.linear.summary());
    page.paragraph(&format!(
        "PD gains fitted with Clarabel to a disk phase margin of at least 45° (the smallest gains \
         that meet it), the independent certificate (closed-loop eigenvalues and margins on a \
         dense frequency grid) and a tilt recovery on the nonlinear model. {}",
        r.findings[4].text
    ));
    page.preformatted(&r.tune.summary());

    // 6. Stability map.
    page.heading(2, "6. Stability map over (Kp, Kd)");
    let kp_n = (r.map.len() as f64).sqrt().round() as usize;
    page.paragraph(&format!(
        "The largest real part of the pitch loop's closed-loop poles over a {kp_n} × {kp_n} grid \
         of PD gains (Kp 0–8000 N/rad, Kd 0–4000 N s/rad), with the stability boundary (its zero \
         contour), computed in memory by the sweep library that `twv sweep` shards across a \
         cluster. {}",
        r.findings[5].text
    ));
    let map = map_of(&r.map, kp_n);
    for (file, fig) in map.figures() {
        add(
            &mut page,
            figure(
                progress,
                &format!("map_{file}"),
                fig,
                "Spectral abscissa of the pitch loop over (Kp, Kd); the line is the stability \
                 boundary (zero contour).",
            )?,
        );
    }

    // 7. The bicycle.
    let b = &r.bicycle;
    page.heading(2, "7. Balancing the bicycle");
    page.paragraph(&format!(
        "The same machinery on a second two-wheeler: the Whipple bicycle of the benchmark of \
         Meijaard et al. (2007), derived by twv from bodies and rolling contacts. Nobody \
         steering, it stays up only between its weave and capsize speeds; below the weave speed \
         a rider must steer into the fall. `twv steer` tunes a steer-torque law on lean, steer \
         and their rates at every speed (Clarabel, closest to an LQR design that meets the \
         margin spec), certifies each speed's gains and checks them on the nonlinear bicycle. \
         {}",
        r.findings[6].text
    ));
    add(
        &mut page,
        figure(
            progress,
            "bicycle_eigenvalues.svg",
            b.steady.figure(),
            "The bicycle's eigenvalues against speed, nobody steering (the benchmark's Fig. 3): \
             self-stable where every real part is negative.",
        )?,
    );
    for (file, fig) in b.steer.figures() {
        let caption = match file.as_str() {
            "gains.svg" => "The tuned steer-gain schedule against speed.",
            "abscissa.svg" => {
                "The largest real part of the eigenvalues, nobody steering and steered by the \
                 schedule."
            }
            _ => "The disk phase margin at the steer-torque input of the steered bicycle.",
        };
        add(
            &mut page,
            figure(progress, &format!("bicycle_{file}"), fig, caption)?,
        );
    }
    let lean = |r: &RideResult, name: &str| {
        let phi = r.columns.iter().position(|c| c == "phi").unwrap_or(1);
        Curve {
            name: name.to_string(),
            points: r.rows.iter().map(|row| (row[0], row[phi])).collect(),
        }
    };
    add(
        &mut page,
        figure(
            progress,
            "bicycle_push.svg",
            crate::plot::Figure::Line(LineChart::new(
                &format!("Whipple bicycle at {PUSH_SPEED} m/s after a {PUSH} rad/s lean-rate push"),
                "t [s]",
                "lean φ [rad]",
                (800, 450),
                vec![
                    lean(&b.unsteered, "nobody steering"),
                    lean(&b.steered, "steered"),
                ],
            )),
            &format!(
                "The lean after the push at {PUSH_SPEED} m/s: {} nobody steering, {} steered by \
                 the schedule's gains.",
                ride_outcome(&b.unsteered),
                ride_outcome(&b.steered)
            ),
        )?,
    );

    page.heading(3, "A measured bicycle within its uncertainty");
    match &b.uncertainty {
        Some(u) => {
            page.paragraph(&uncertainty_text(u));
            for (file, fig) in u.figures() {
                let caption = if file == "speeds.svg" {
                    "The fraction of draws whose weave (capsize) speed is at most v: the \
                     spread the measured parameters' stated uncertainty gives the self-stable \
                     band; the vertical lines are the nominal bicycle's."
                } else {
                    "The fraction of draws whose disk phase margin at the steer torque is at \
                     most the abscissa, steered by the design tuned on the nominal values."
                };
                add(
                    &mut page,
                    figure(
                        progress,
                        &format!("bicycle_uncertainty_{file}"),
                        fig,
                        caption,
                    )?,
                );
            }
        }
        None => page.paragraph(
            "No measured bicycle with an [uncertainty] table was given to this report, so this \
             part was not computed.",
        ),
    }

    // 8. Claims.
    page.heading(2, "8. The study's claims, checked");
    let rows: Vec<Vec<String>> = r
        .claims
        .iter()
        .map(|c| vec![c.claim.clone(), c.verdict.clone(), c.evidence.clone()])
        .collect();
    page.table(&["study's claim", "verdict", "evidence"], &rows);
    page.paragraph(&format!(
        "Generated by twv {} in {:.1} s on {}.",
        env!("CARGO_PKG_VERSION"),
        r.wall_time_s,
        r.machine
    ));
    Ok((page.finish("twv report"), figures))
}

/// The Monte Carlo in words, every number from the run.
fn uncertainty_text(u: &UncertaintyResult) -> String {
    let band = match (u.weave_speed, u.capsize_speed) {
        (Some(w), Some(c)) => format!(
            "in 90 % of the draws that have a self-stable band (5–95 %) its weave speed lies \
             between {:.2} and {:.2} m/s and its capsize speed between {:.2} and {:.2} m/s",
            w.p05, w.p95, c.p05, c.p95
        ),
        _ => "no draw has a self-stable band".to_string(),
    };
    let nominal = match (u.nominal.weave_speed, u.nominal.capsize_speed) {
        (Some(w), Some(c)) => format!("self-stable from {w:.2} to {c:.2} m/s"),
        _ => "self-stable at no speed searched".to_string(),
    };
    format!(
        "{} parameters of {} vary within their stated standard deviations ({} draws, seed \
         {}). Nominally the bicycle is {nominal}; {band}, and {} of {} draws are self-stable \
         somewhere between {} and {} m/s. Steered at {} m/s by the gains tuned on the nominal \
         values to `{}`, the closed loop is stable in {} of {} draws and meets the spec in {}.",
        u.varied.len(),
        u.params,
        u.samples.len(),
        u.seed,
        u.self_stable,
        u.physical,
        u.lo,
        u.hi,
        u.speed,
        u.spec,
        u.stable,
        u.physical,
        u.meets_spec
    )
}

/// How a push ride ended, in words, from its verdict.
fn ride_outcome(ride: &RideResult) -> &'static str {
    match ride.verdict {
        RideVerdict::Fell => "it falls",
        RideVerdict::Recovered => "the lean dies out",
        RideVerdict::NotRecovered => "the lean neither falls nor dies out within the run",
        RideVerdict::Undisturbed => "nothing moved",
    }
}

/// The in-memory map of the report's sweep, for its figure and CSV.
fn map_of(points: &[PointResult], n: usize) -> crate::sweep::Map {
    let grid = Grid::study_gains(n);
    crate::sweep::Map::in_memory("vehicle8", grid, Metric::SpectralAbscissa, points.to_vec())
}

fn pretty<T: Serialize>(value: &T) -> String {
    serde_json::to_string_pretty(value).unwrap_or_default()
}

/// The data files beside the page.
pub fn data_files(r: &ReportResults) -> Vec<(String, String)> {
    let n = (r.map.len() as f64).sqrt().round() as usize;
    let mut out = vec![
        ("data/model_terms.txt".to_string(), r.model.terms.clone()),
        ("data/audit.json".to_string(), pretty(&r.audit)),
        (
            "data/lyapunov_running.csv".to_string(),
            r.lyapunov_preset.running_csv(),
        ),
        ("data/phase.csv".to_string(), r.phase.csv()),
        ("data/phase.json".to_string(), pretty(&r.phase)),
        ("data/map.csv".to_string(), map_of(&r.map, n).csv()),
    ];
    out.push((
        "data/bicycle_steady.csv".to_string(),
        r.bicycle.steady.csv(),
    ));
    out.push(("data/bicycle_steer.csv".to_string(), r.bicycle.steer.csv()));
    if let Some(u) = &r.bicycle.uncertainty {
        out.push(("data/bicycle_uncertainty.csv".to_string(), u.csv()));
    }
    for sim in &r.recovery {
        out.push((
            format!("data/{}.csv", sim.scenario.replace(' ', "_")),
            sim.csv(),
        ));
    }
    out
}
