//! `twv phase`: phase portraits (Φ, Φ̇) — closed loop for several PID gain sets side by side
//! (the study's Fig. 4 a–d), or open loop under constant external forces.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use twv_analysis::api::{portraits, Drive, PhaseSettings};

use super::interrupted_or;
use crate::common::{
    parse_gains, parse_vector, print_result, split_sets, write_files, Context, ControllerArgs,
    ModelArgs, Outcome, RunArgs,
};

/// Phase portraits (Φ, dΦ/dt) for several gain sets, or for constant external forces.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct PhaseArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Gain sets "Kp,Ki,Kd;Kp,Ki,Kd;…" [N/rad, N/(rad s), N s/rad] [default: four sets retracing
    /// the study's Fig. 4: (a) 3860,1.2e5,1980 (Ki above the Routh–Hurwitz limit: growing
    /// oscillation), (b) 3860,3e4,1980 (stable, slow oscillation), (c) 1000,0,300 (Kp < M_x g:
    /// a saddle, leaving along a line), (d) 3860,0,1980 (the study's PD)]
    #[arg(
        long,
        value_name = "SETS",
        conflicts_with = "force",
        allow_hyphen_values = true
    )]
    pub gains: Option<String>,
    /// Open loop instead: constant inputs "U1,U2;U1,U2;…" in the model's input order (F1 [N],
    /// T2 [N m] for vehicle8/vehicle7; τ_L, τ_R [N m] for segway7), one portrait per set
    #[arg(long, value_name = "SETS", allow_hyphen_values = true)]
    pub force: Option<String>,
    /// Initial states "x0;x0;…", each comma-separated in the model's state order [default: at
    /// rest with Φ = 0.1, −0.1, 0.2, −0.2 rad]
    #[arg(long, value_name = "STATES", allow_hyphen_values = true)]
    pub x0: Option<String>,
    #[command(flatten)]
    pub controller: ControllerArgs,
    #[command(flatten)]
    pub run: RunArgs,
    /// Write phase_1.svg … (one per set), phase.svg (two to a row), their PNGs, phase.csv,
    /// phase.json
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the result as JSON on stdout
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &PhaseArgs, ctx: &Context) -> Result<Outcome> {
    let model = args.model.resolve(ctx)?;
    let mut settings = PhaseSettings {
        run: args.run.settings(10.0),
        ..PhaseSettings::default()
    };
    match (&args.force, &args.gains) {
        (Some(_), _) if args.controller.any() => {
            bail!("--force runs the open loop: controller options do not apply")
        }
        (Some(text), _) => {
            let sets = split_sets(text);
            if sets.is_empty() {
                bail!("--force: no input sets in `{text}` (use \"F1,T2;F1,T2\")");
            }
            settings.portraits = sets
                .into_iter()
                .map(|s| {
                    Ok((
                        format!("open loop, u = ({s})"),
                        Drive::Open(parse_vector("force", s)?),
                    ))
                })
                .collect::<Result<_>>()?;
        }
        (None, Some(text)) => {
            let sets = split_sets(text);
            if sets.is_empty() {
                bail!("--gains: no gain sets in `{text}` (use \"Kp,Ki,Kd;Kp,Ki,Kd\")");
            }
            settings.portraits = sets
                .into_iter()
                .map(|s| {
                    let g = parse_gains("gains", s)?;
                    let label = format!("Kp {} Ki {} Kd {}", g.kp, g.ki, g.kd);
                    Ok((label, Drive::Closed(args.controller.settings(g, None)?)))
                })
                .collect::<Result<_>>()?;
        }
        (None, None) => {
            // The study's four sets, with the controller options applied to each.
            for (_, drive) in &mut settings.portraits {
                if let Drive::Closed(c) = drive {
                    *c = args.controller.settings(c.pitch.gains, None)?;
                }
            }
        }
    }
    if let Some(text) = &args.x0 {
        let sets = split_sets(text);
        if sets.is_empty() {
            bail!("--x0: no initial states in `{text}`");
        }
        settings.x0 = Some(
            sets.into_iter()
                .map(|s| parse_vector("x0", s))
                .collect::<Result<_>>()?,
        );
    }
    let bar = ctx.bar();
    let out = match interrupted_or(portraits(&model, &settings, &bar), "the portraits")? {
        Ok(out) => out,
        Err(outcome) => return Ok(outcome),
    };
    if let Some(dir) = &args.out {
        write_files(ctx, dir, &out.files()?)?;
    }
    print_result(&out, args.json, || out.summary())?;
    Ok(Outcome::Done)
}
