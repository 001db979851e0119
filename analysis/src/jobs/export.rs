//! `export`: a model for other people's tools, an FMI 2.0 FMU or a CasADi external function.

use serde::Serialize;
use serde_json::{json, Value};

use super::options::{as_bool, as_text, field, flag, is_none, number, Kind, Opt};
use super::{Job, JobOutput};
use crate::error::{Error, Result};
use crate::export::{self, casadi, fmu, ExportFormat, ExportSettings};
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;

/// The export.
pub struct Export;

/// What an export wrote.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Exported {
    /// Model name.
    pub model: String,
    /// `fmu` or `casadi`.
    pub format: String,
    /// The file (`<id>.fmu`, `lib<id>.so`).
    pub file: String,
    /// The model identifier.
    pub model_identifier: String,
    /// The FMU's GUID (a hash of the model and its values); `None` for a CasADi library.
    pub guid: Option<String>,
    /// Size of the file [bytes].
    pub bytes: usize,
    /// SHA-256 of the file.
    pub sha256: String,
    /// What the library runs: generated code of a shipped model, or the IR interpreter.
    pub engine: String,
    /// Whether the parameters are tunable variables.
    pub tunable: bool,
    /// The file's bytes.
    #[serde(skip)]
    pub data: Vec<u8>,
}

fn set_format(format: ExportFormat) -> impl Fn(&mut ExportSettings, &Value) -> Result<()> {
    move |s, v| {
        if as_bool(format.name(), v)? {
            s.format = format;
        }
        Ok(())
    }
}

impl Job for Export {
    const NAME: &'static str = "export";
    const SUMMARY: &'static str =
        "Export the model for other tools: an FMI 2.0 FMU (model exchange and co-simulation) \
         or a CasADi external function with its Jacobian";
    const SERVED: bool = false;
    const FILES: &'static str = "<id>.fmu or lib<id>.so, and export.json";
    type Settings = ExportSettings;
    type Output = Exported;

    fn options() -> Vec<Opt<ExportSettings>> {
        vec![
            Opt::new(
                "format",
                Kind::Choice,
                "",
                "fmu: an FMI 2.0 FMU for model exchange and co-simulation; casadi: a shared \
                 library with CasADi's external-function API (f and jac_f)",
                |s: &mut ExportSettings, v| {
                    s.format = match as_text("format", v)? {
                        "casadi" => ExportFormat::Casadi,
                        _ => ExportFormat::Fmu,
                    };
                    Ok(())
                },
                |s| json!(s.format.name()),
            )
            .choices(&["fmu", "casadi"]),
            Opt::new(
                "fmu",
                Kind::Flag,
                "",
                "Short for --format fmu",
                set_format(ExportFormat::Fmu),
                |s| json!(s.format == ExportFormat::Fmu),
            )
            .conflicts(&["format", "casadi"]),
            Opt::new(
                "casadi",
                Kind::Flag,
                "",
                "Short for --format casadi",
                set_format(ExportFormat::Casadi),
                |s| json!(s.format == ExportFormat::Casadi),
            )
            .conflicts(&["format", "fmu"]),
            flag(
                "tunable",
                "Parameters as tunable FMU variables, settable before and during a run \
                 (default: fixed at the model's values)",
                field(|s: &mut ExportSettings| &mut s.tunable),
            ),
            number(
                "rk4_step",
                "s",
                "The largest RK4 step of one co-simulation step (fmi2DoStep); also the default \
                 experiment's step size",
                field(|s: &mut ExportSettings| &mut s.rk4_step),
            ),
            number(
                "stop_time",
                "s",
                "Stop time of the FMU's default experiment",
                field(|s: &mut ExportSettings| &mut s.stop_time),
            ),
            Opt::new(
                "name",
                Kind::Text,
                "",
                "Model identifier: the file names and the FMI modelIdentifier (none: twv_<model>)",
                |s: &mut ExportSettings, v| {
                    s.name = if is_none(v) {
                        None
                    } else {
                        Some(as_text("name", v)?.to_string())
                    };
                    Ok(())
                },
                |s| json!(s.name),
            ),
        ]
    }

    fn validate(s: &ExportSettings) -> Result<()> {
        s.validate()
    }

    fn run(model: &ResolvedModel, s: &ExportSettings, _p: &dyn Progress) -> Result<Exported> {
        s.validate()?;
        let bundle = export::bundle(model, s)?;
        let id = export::identifier(model, s);
        let runtime = export::runtime()?;
        let (file, data, guid) = match s.format {
            ExportFormat::Fmu => (
                format!("{id}.fmu"),
                fmu::archive(&model.ir, &bundle, &id, &runtime, s)?,
                Some(bundle.guid()),
            ),
            ExportFormat::Casadi => (
                casadi::file_name(&id),
                casadi::library(&bundle, &runtime),
                None,
            ),
        };
        let engine = if twv_generated::is_generated(model.ir.hash()) {
            "generated"
        } else {
            "interpreter"
        };
        Ok(Exported {
            model: model.name().to_string(),
            format: s.format.name().to_string(),
            sha256: twv_ir::sha256_hex_bytes(&data),
            bytes: data.len(),
            file,
            model_identifier: id,
            guid,
            engine: engine.to_string(),
            tunable: s.tunable,
            data,
        })
    }
}

impl JobOutput for Exported {
    fn summary(&self) -> String {
        format!(
            "{} of {} ({}, {} code, parameters {}): {} bytes, {}\n",
            self.format,
            self.model,
            self.file,
            self.engine,
            if self.tunable { "tunable" } else { "fixed" },
            self.bytes,
            self.sha256
        )
    }

    fn files(&self) -> Result<Files> {
        if self.data.is_empty() {
            return Err(Error::input("export", "nothing was built"));
        }
        let mut f = Files::new();
        f.entries.push((self.file.clone(), self.data.clone()));
        f.json("export.json", self);
        Ok(f)
    }
}
