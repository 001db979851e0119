//! What the commands share: the context (embedded vehicles, --quiet, the interrupt flag), the
//! model's flags, printing, writing files, and error messages.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use clap::Args;
use twv_analysis::api::CancelFlag;
use twv_analysis::model::{
    Compiler, IrRuntime, ModelSource, ModelSpec, ParamSource, ResolvedModel,
};
use twv_analysis::output::Files;

use crate::progress::Bar;

/// How a command ended (errors are the `Err` of its `Result`).
#[derive(Debug)]
pub enum Outcome {
    /// Done, with a positive (or no) verdict.
    Done,
    /// Done, but the verdict is negative: the message says which; exit code 3.
    Negative(String),
    /// Interrupted; the message says what was kept; exit code 130.
    Interrupted(String),
}

/// Raised by Ctrl-C (SIGINT) or SIGTERM; jobs check it between chunks of work.
pub static CANCEL: CancelFlag = CancelFlag::new();

/// The first interrupt asks the running job to stop cleanly (a sweep then writes its
/// checkpoint); a second one exits at once, except that a file being written (a checkpoint) is
/// finished and renamed into place first (at most [`LAST_WRITE_WAIT`]).
pub fn install_interrupt_handler() {
    let _ = ctrlc::set_handler(|| {
        if CANCEL.is_raised() {
            let started = std::time::Instant::now();
            while twv_analysis::output::writes_in_flight() > 0
                && started.elapsed() < LAST_WRITE_WAIT
            {
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
            std::process::exit(130);
        }
        CANCEL.raise();
    });
}

/// The longest a second Ctrl-C waits for a file being written.
const LAST_WRITE_WAIT: std::time::Duration = std::time::Duration::from_secs(10);

/// What every command may need besides its arguments.
pub struct Context {
    paper: &'static str,
    segway: &'static str,
    /// `--quiet`.
    pub quiet: bool,
}

impl Context {
    /// The context of this run.
    pub fn new(paper: &'static str, segway: &'static str, quiet: bool) -> Self {
        Self {
            paper,
            segway,
            quiet,
        }
    }

    /// The embedded default parameter file of a shipped vehicle, if it has one.
    pub fn vehicle_defaults(&self, model: &str) -> Option<ParamSource> {
        twv_analysis::model::vehicle_defaults(model, self.paper, self.segway)
    }

    /// The embedded vehicles/paper.toml.
    pub fn paper_toml(&self) -> &'static str {
        self.paper
    }

    /// A progress bar for a job (shown on a terminal after 2 s unless `--quiet`).
    pub fn bar(&self) -> Bar {
        Bar::new(!self.quiet && std::io::stderr().is_terminal(), &CANCEL)
    }

    /// An informational line on stderr, unless `--quiet`.
    pub fn say(&self, line: impl std::fmt::Display) {
        if !self.quiet {
            eprintln!("{line}");
        }
    }
}

/// The one-line message for an error: a bad setting names the command-line option.
///
/// The library names the settings field; for the job `command` that is the flag of the option
/// with that name or alias (`repeat` is `--runs`), and a field that no flag sets (a settings
/// file's) is named as the settings field it is, never as a flag that does not exist.
pub fn describe(err: &anyhow::Error, command: &str) -> String {
    if let Some(twv_analysis::Error::Input { field, reason }) = err.downcast_ref() {
        let options = twv_analysis::jobs::find(command).map_or(Vec::new(), |j| j.options());
        let option = options
            .iter()
            .find(|o| o.name == field || o.aliases.contains(&field.as_str()));
        let line = match option {
            Some(o) => format!("--{}: {reason}", crate::job::flag_name(o.name)),
            None if options.is_empty() => format!("{field}: {reason}"),
            None => format!("settings field `{field}`: {reason}"),
        };
        return twv_analysis::error::readable(&line);
    }
    twv_analysis::error::readable(&format!("{err:#}"))
}

/// Which model to run and with which parameters.
#[derive(Args, Debug, Clone, Default)]
pub struct ModelArgs {
    /// Shipped model: vehicle8, vehicle7, segway7, lorenz, henon_heiles or whipple (the bicycle) [default: vehicle8]
    #[arg(long, value_name = "NAME", conflicts_with = "ir")]
    pub model: Option<String>,
    /// A model IR file (twv-ir/1) to run without recompiling twv (see --runtime)
    #[arg(long, value_name = "FILE")]
    pub ir: Option<PathBuf>,
    /// Parameter file (TOML, SI units) [default: for the vehicles vehicles/paper.toml
    /// (segway7: vehicles/segway.toml), embedded in the binary; otherwise the IR's defaults]
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// How a model without generated code (--ir, whipple) runs: `jit` compiles it to native
    /// code when it is loaded (Cranelift; the interpreter's bits), `interpreter` interprets it
    /// (the reference) [default: jit in a build with the `jit` feature, else interpreter]
    #[arg(long, value_name = "RUNTIME", value_parser = ["jit", "interpreter"])]
    pub runtime: Option<String>,
}

/// Whether this build has the JIT.
pub const HAS_JIT: bool = cfg!(feature = "jit");

/// The JIT of a build with the `jit` feature.
#[cfg(feature = "jit")]
const JIT: Option<IrRuntime> = Some(IrRuntime::Compiled(Compiler {
    name: "cranelift",
    compile: |ir| twv_jit::compile(ir).map_err(|e| e.to_string()),
}));

#[cfg(not(feature = "jit"))]
const JIT: Option<IrRuntime> = None;

/// `--runtime`'s value (see [`ModelArgs::runtime`]).
fn runtime(given: Option<&str>) -> IrRuntime {
    match (given, JIT) {
        (Some("interpreter"), _) | (None, None) => IrRuntime::Interpreter,
        (_, Some(jit)) => jit,
        (Some(_), None) => IrRuntime::Compiled(Compiler {
            name: "none",
            compile: |_| {
                Err(
                    "this twv was built without the JIT (--no-default-features): rebuild it \
                     with the default features or run `--runtime interpreter`"
                        .to_string(),
                )
            },
        }),
    }
}

impl ModelArgs {
    /// The spec these arguments name.
    pub fn spec(&self, ctx: &Context) -> ModelSpec {
        let (model, shipped) = match (&self.ir, &self.model) {
            (Some(path), _) => (ModelSource::IrFile(path.clone()), None),
            (None, name) => {
                let name = name
                    .clone()
                    .unwrap_or_else(|| twv_analysis::model::DEFAULT_MODEL.into());
                (ModelSource::Shipped(name.clone()), Some(name))
            }
        };
        let params = match (&self.params, shipped) {
            (Some(p), _) => ParamSource::File(p.clone()),
            (None, Some(name)) => ctx.vehicle_defaults(&name).unwrap_or_default(),
            (None, None) => ParamSource::Defaults,
        };
        ModelSpec {
            model,
            params,
            runtime: runtime(self.runtime.as_deref()),
        }
    }

    /// The resolved model.
    pub fn resolve(&self, ctx: &Context) -> Result<ResolvedModel> {
        Ok(self.spec(ctx).resolve()?)
    }
}

/// Writes `files` into `dir` (atomically, all or nothing) and names them on stderr.
pub fn write_files(ctx: &Context, dir: &Path, files: &Files) -> Result<()> {
    let written = files.write(dir)?;
    for path in &written.files {
        ctx.say(format!("wrote {}", path.display()));
    }
    for note in &written.left {
        ctx.say(format!("note: {note}"));
    }
    Ok(())
}

/// Text on stdout; a failed write (a full disk, /dev/full) is an error, not a panic.
pub fn print(text: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .context("cannot write to stdout")
}
