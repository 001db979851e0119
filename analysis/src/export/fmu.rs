//! An FMI 2.0 FMU: `modelDescription.xml` from the IR (names, units and descriptions of every
//! variable, the derivatives' dependencies from the Jacobians' sparsity), the export runtime as
//! `binaries/linux64/<id>.so`, the model in `resources/bundle.json` and a page in
//! `documentation/index.html`, zipped with fixed timestamps (the same export, the same bytes).
//! The layout and attributes follow the Modelica Association's Reference FMUs.

use std::collections::BTreeSet;
use std::io::Write;

use twv_ir::{Bundle, Ir, ValueReferences, Variable, FMU_RESOURCE};

use super::xml::{escape, Writer};
use super::ExportSettings;
use crate::error::{Error, Result};

/// The unit of a state's derivative: `rad` → `rad/s`, `m/s` → `m/s2`, none → `1/s`.
pub fn derivative_unit(unit: &str) -> String {
    match unit {
        "" => "1/s".into(),
        u if u.ends_with("/s") => format!("{u}2"),
        u => format!("{u}/s"),
    }
}

/// A number as the XML's attributes write it (shortest round-trip form).
fn number(x: f64) -> String {
    format!("{x:?}")
}

/// The 1-based indices (in `ModelVariables`) that derivative `i` depends on: the states and
/// inputs of row `i`'s structural non-zeros of ∂f/∂x and ∂f/∂u.
fn dependencies(ir: &Ir, refs: &ValueReferences, i: usize) -> Vec<usize> {
    let mut deps = BTreeSet::new();
    for (function, var) in [
        ("jac_x", Variable::State as fn(usize) -> Variable),
        ("jac_u", Variable::Input),
    ] {
        if let Some(o) = ir.output(function, function) {
            for (r, c, _) in o.entries() {
                if r == i {
                    deps.insert(refs.of(var(c)) as usize + 1);
                }
            }
        }
    }
    deps.into_iter().collect()
}

/// `modelDescription.xml` of `ir` exported as `id` with `bundle`.
pub fn model_description(ir: &Ir, bundle: &Bundle, id: &str, settings: &ExportSettings) -> String {
    let (nx, nu) = (ir.nx(), ir.nu());
    let np = if bundle.tunable { ir.np() } else { 0 };
    let refs = ValueReferences { nx, nu, np };
    let s = |x: &str| x.to_string();
    let mut w = Writer::new();
    w.open(
        "fmiModelDescription",
        &[
            ("fmiVersion", s("2.0")),
            ("modelName", s(ir.model())),
            ("guid", bundle.guid()),
            ("description", s(ir.description())),
            (
                "generationTool",
                format!("twv {}", env!("CARGO_PKG_VERSION")),
            ),
            ("variableNamingConvention", s("structured")),
            ("numberOfEventIndicators", s("0")),
        ],
    );
    let common = |cs: bool| {
        let mut a = vec![
            ("modelIdentifier", s(id)),
            ("needsExecutionTool", s("false")),
            ("canBeInstantiatedOnlyOncePerProcess", s("false")),
            ("canNotUseMemoryManagementFunctions", s("true")),
            ("canGetAndSetFMUstate", s("true")),
            ("canSerializeFMUstate", s("true")),
            ("providesDirectionalDerivative", s("true")),
        ];
        if cs {
            a.extend([
                ("canHandleVariableCommunicationStepSize", s("true")),
                ("canInterpolateInputs", s("false")),
                ("maxOutputDerivativeOrder", s("0")),
                ("canRunAsynchronuously", s("false")),
            ]);
        } else {
            a.push(("completedIntegratorStepNotNeeded", s("true")));
        }
        a
    };
    w.empty("ModelExchange", &common(false));
    w.empty("CoSimulation", &common(true));

    let mut units = BTreeSet::new();
    for st in ir.states() {
        units.insert(st.unit.clone());
        units.insert(derivative_unit(&st.unit));
    }
    units.extend(ir.inputs().iter().map(|u| u.unit.clone()));
    if bundle.tunable {
        units.extend(ir.params().iter().map(|p| p.unit.clone()));
    }
    units.remove("");
    w.open("UnitDefinitions", &[]);
    for u in &units {
        w.empty("Unit", &[("name", u.clone())]);
    }
    w.close("UnitDefinitions");
    w.open("LogCategories", &[]);
    w.empty(
        "Category",
        &[
            ("name", s("logStatusError")),
            ("description", s("Refused calls")),
        ],
    );
    w.empty(
        "Category",
        &[
            ("name", s("logStatusFatal")),
            ("description", s("Failures")),
        ],
    );
    w.close("LogCategories");
    w.empty(
        "DefaultExperiment",
        &[
            ("startTime", s("0")),
            ("stopTime", number(settings.stop_time)),
            ("stepSize", number(settings.rk4_step)),
        ],
    );

    w.open("ModelVariables", &[]);
    let real = |w: &mut Writer, unit: &str, extra: Vec<(&str, String)>| {
        let mut a = Vec::new();
        if !unit.is_empty() {
            a.push(("unit", unit.to_string()));
        }
        a.extend(extra);
        w.empty("Real", &a);
    };
    for (i, st) in ir.states().iter().enumerate() {
        w.open(
            "ScalarVariable",
            &[
                ("name", st.name.clone()),
                ("valueReference", refs.of(Variable::State(i)).to_string()),
                ("description", st.description.clone()),
                ("causality", s("output")),
                ("variability", s("continuous")),
                ("initial", s("exact")),
            ],
        );
        real(&mut w, &st.unit, vec![("start", s("0"))]);
        w.close("ScalarVariable");
    }
    for (i, st) in ir.states().iter().enumerate() {
        w.open(
            "ScalarVariable",
            &[
                ("name", format!("der({})", st.name)),
                (
                    "valueReference",
                    refs.of(Variable::Derivative(i)).to_string(),
                ),
                ("description", format!("time derivative of {}", st.name)),
                ("causality", s("local")),
                ("variability", s("continuous")),
                ("initial", s("calculated")),
            ],
        );
        let index = refs.of(Variable::State(i)) + 1;
        real(
            &mut w,
            &derivative_unit(&st.unit),
            vec![("derivative", index.to_string())],
        );
        w.close("ScalarVariable");
    }
    for (j, input) in ir.inputs().iter().enumerate() {
        w.open(
            "ScalarVariable",
            &[
                ("name", input.name.clone()),
                ("valueReference", refs.of(Variable::Input(j)).to_string()),
                ("description", input.description.clone()),
                ("causality", s("input")),
                ("variability", s("continuous")),
            ],
        );
        real(&mut w, &input.unit, vec![("start", s("0"))]);
        w.close("ScalarVariable");
    }
    for k in 0..np {
        let p = &ir.params()[k];
        w.open(
            "ScalarVariable",
            &[
                ("name", p.name.clone()),
                ("valueReference", refs.of(Variable::Param(k)).to_string()),
                ("description", p.description.clone()),
                ("causality", s("parameter")),
                ("variability", s("tunable")),
                ("initial", s("exact")),
            ],
        );
        real(&mut w, &p.unit, vec![("start", number(bundle.params[k]))]);
        w.close("ScalarVariable");
    }
    w.close("ModelVariables");

    w.open("ModelStructure", &[]);
    w.open("Outputs", &[]);
    for i in 0..nx {
        let index = (refs.of(Variable::State(i)) + 1).to_string();
        w.empty(
            "Unknown",
            &[
                ("index", index.clone()),
                ("dependencies", index),
                ("dependenciesKind", s("constant")),
            ],
        );
    }
    w.close("Outputs");
    w.open("Derivatives", &[]);
    for i in 0..nx {
        let deps = dependencies(ir, &refs, i);
        let list = |f: &dyn Fn(&usize) -> String| deps.iter().map(f).collect::<Vec<_>>().join(" ");
        w.empty(
            "Unknown",
            &[
                ("index", (refs.of(Variable::Derivative(i)) + 1).to_string()),
                ("dependencies", list(&|d| d.to_string())),
                ("dependenciesKind", list(&|_| s("dependent"))),
            ],
        );
    }
    w.close("Derivatives");
    w.open("InitialUnknowns", &[]);
    for i in 0..nx {
        let index = (refs.of(Variable::Derivative(i)) + 1).to_string();
        w.empty("Unknown", &[("index", index)]);
    }
    w.close("InitialUnknowns");
    w.close("ModelStructure");
    w.close("fmiModelDescription");
    w.finish()
}

/// `documentation/index.html`: what the FMU is and where it came from.
fn documentation(ir: &Ir, bundle: &Bundle, id: &str) -> String {
    let rows = |signals: &[twv_ir::Signal]| -> String {
        signals
            .iter()
            .map(|v| {
                format!(
                    "<tr><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                    escape(&v.name),
                    escape(&v.unit),
                    escape(&v.description)
                )
            })
            .collect()
    };
    let params: String = ir
        .params()
        .iter()
        .zip(&bundle.params)
        .map(|(p, v)| {
            format!(
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                escape(&p.name),
                v,
                escape(&p.unit),
                escape(&p.description)
            )
        })
        .collect();
    let how = if bundle.tunable {
        "tunable parameters (causality parameter): set them before or during a run"
    } else {
        "fixed at these values (export again with other --params to change them)"
    };
    format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{id}</title>\n\
         <style>body{{font-family:sans-serif;max-width:50em;margin:2em auto;line-height:1.4}}\
         td,th{{padding:0.2em 0.6em;text-align:left}}</style></head><body>\n\
         <h1>{model}</h1>\n<p>{description}</p>\n\
         <p>An FMI 2.0 FMU for model exchange and co-simulation, exported by twv {version} from \
         the model IR {hash}. Co-simulation steps with fixed-step RK4 of at most {step} s (the \
         classical Runge–Kutta method, as <code>twv ride</code>); the directional derivatives \
         are the model's Jacobians ∂f/∂x and ∂f/∂u. Every state is an output.</p>\n\
         <h2>States</h2><table><tr><th>name</th><th>unit</th><th>meaning</th></tr>\n{states}</table>\n\
         <h2>Inputs</h2><table><tr><th>name</th><th>unit</th><th>meaning</th></tr>\n{inputs}</table>\n\
         <h2>Parameters</h2><p>From {origin}; {how}.</p>\n\
         <table><tr><th>name</th><th>value</th><th>unit</th><th>meaning</th></tr>\n{params}</table>\n\
         </body></html>\n",
        model = escape(ir.model()),
        description = escape(ir.description()),
        version = env!("CARGO_PKG_VERSION"),
        hash = escape(ir.hash()),
        step = bundle.rk4_step,
        states = rows(ir.states()),
        inputs = rows(ir.inputs()),
        origin = escape(&bundle.params_origin),
    )
}

/// The FMU archive.
pub fn archive(
    ir: &Ir,
    bundle: &Bundle,
    id: &str,
    runtime: &[u8],
    settings: &ExportSettings,
) -> Result<Vec<u8>> {
    let files: [(String, Vec<u8>, u32); 4] = [
        (
            "modelDescription.xml".into(),
            model_description(ir, bundle, id, settings).into_bytes(),
            0o644,
        ),
        (format!("binaries/linux64/{id}.so"), runtime.to_vec(), 0o755),
        (
            format!("resources/{FMU_RESOURCE}"),
            bundle.to_json().into_bytes(),
            0o644,
        ),
        (
            "documentation/index.html".into(),
            documentation(ir, bundle, id).into_bytes(),
            0o644,
        ),
    ];
    let zip_error = |e: zip::result::ZipError| Error::input("fmu", format!("cannot zip: {e}"));
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    for (name, bytes, mode) in &files {
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated)
            .last_modified_time(zip::DateTime::default())
            .unix_permissions(*mode);
        zip.start_file(name.as_str(), options).map_err(zip_error)?;
        zip.write_all(bytes)
            .map_err(|e| Error::input("fmu", format!("cannot zip {name}: {e}")))?;
    }
    Ok(zip.finish().map_err(zip_error)?.into_inner())
}
