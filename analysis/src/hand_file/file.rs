//! Reading a hand file (TOML) against a model IR: every formula parsed with the model's own
//! state, input and parameter names, every entry checked to be there once, each problem one line
//! naming the file, the line (and column) and the name.

use std::collections::BTreeMap;

use serde::Deserialize;
use toml::Spanned;
use twv_ir::Ir;

use super::expr::{Expr, Var};
use super::parse::{parse, ParseError, Scope};

/// A hand file that does not read or does not fit the model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}{}: {message}", match line { 0 => String::new(), n => format!(":{n}") })]
pub struct HandFileError {
    /// The file (as the user named it).
    pub file: String,
    /// 1-based line (0: the file as a whole).
    pub line: usize,
    /// What is wrong, naming the entry or name.
    pub message: String,
}

/// One formula of the file with the line it is on.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    pub expr: Expr,
    pub line: usize,
}

/// The equations a hand file gives.
#[derive(Debug, Clone, PartialEq)]
pub enum HandForm {
    /// Poincaré's form M(q) ṗ + Cp(q, p) + F(q) = Q(q, u) with the kinematics q̇(q, p).
    Mechanical {
        /// M by rows, in the model's speed order.
        mass: Vec<Vec<Entry>>,
        /// Cp, one per speed (Σ_j C[i, j] p_j when the file gives the matrix C).
        velocity: Vec<Entry>,
        /// True when the file gave C(q, p) rather than Cp.
        from_coriolis_matrix: bool,
        /// F, one per speed.
        gravity: Vec<Entry>,
        /// Q, one per speed.
        inputs: Vec<Entry>,
        /// q̇, one per coordinate.
        qdot: Vec<Entry>,
    },
    /// Only ẋ = f(x, u), one per state.
    Explicit { f: Vec<Entry> },
    /// The equations linearised about the model's steady motion (the bicycle benchmark's form),
    /// M q̈ + v C1 q̇ + (g K0 + v² K2) q = f, q the coordinates of the steady motion's modes;
    /// formulas in the parameters only.
    Linear {
        /// q: the modes' coordinates (the first half of `mechanics.steady_motion.modes`).
        coordinates: Vec<String>,
        /// Their rates among the modes (the second half).
        rates: Vec<String>,
        mass: Vec<Vec<Entry>>,
        c1: Vec<Vec<Entry>>,
        k0: Vec<Vec<Entry>>,
        k2: Vec<Vec<Entry>>,
    },
}

/// A user's hand model, read against one model IR.
#[derive(Debug, Clone, PartialEq)]
pub struct HandModel {
    /// The file name messages and reports use.
    pub origin: String,
    /// The model the file says it is for (`model = "…"`), if it says.
    pub model: Option<String>,
    /// The equations.
    pub form: HandForm,
}

/// A formula: TOML text, or a plain number (`0`, `9.81`).
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
enum Formula {
    Text(String),
    Integer(i64),
    Float(f64),
}

type Vector = Spanned<BTreeMap<String, Spanned<Formula>>>;
type Matrix = Spanned<BTreeMap<String, Spanned<Vec<Spanned<Formula>>>>>;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Document {
    model: Option<Spanned<String>>,
    #[serde(rename = "let")]
    lets: Option<BTreeMap<String, Spanned<Formula>>>,
    #[serde(rename = "M")]
    mass: Option<Matrix>,
    #[serde(rename = "Cp")]
    velocity: Option<Vector>,
    #[serde(rename = "C")]
    coriolis: Option<Matrix>,
    #[serde(rename = "F")]
    gravity: Option<Vector>,
    #[serde(rename = "Q")]
    inputs: Option<Vector>,
    qdot: Option<Vector>,
    f: Option<Vector>,
    linear: Option<LinearTables>,
}

/// `[linear.M]`, `[linear.C1]`, `[linear.K0]`, `[linear.K2]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LinearTables {
    #[serde(rename = "M")]
    mass: Option<Matrix>,
    #[serde(rename = "C1")]
    c1: Option<Matrix>,
    #[serde(rename = "K0")]
    k0: Option<Matrix>,
    #[serde(rename = "K2")]
    k2: Option<Matrix>,
}

impl Formula {
    /// The formula as text (a plain number as it reads).
    fn text(&self) -> String {
        match self {
            Formula::Text(t) => t.clone(),
            Formula::Integer(i) => i.to_string(),
            Formula::Float(f) => f.to_string(),
        }
    }
}

/// Where offsets of the file are.
struct Source<'a> {
    text: &'a str,
    origin: &'a str,
    /// The model's names, appended to an unknown-name error.
    names: String,
    /// The byte offset where each line starts (a line is found by bisection: a file of many
    /// formulas must not be scanned once per formula).
    line_starts: Vec<usize>,
}

impl<'a> Source<'a> {
    fn new(text: &'a str, origin: &'a str, names: String) -> Self {
        let line_starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Self {
            text,
            origin,
            names,
            line_starts,
        }
    }

    fn toml_error(&self, e: &toml::de::Error) -> HandFileError {
        HandFileError {
            file: self.origin.to_string(),
            line: e.span().map_or(0, |s| self.line(s.start)),
            message: e.message().trim().to_string(),
        }
    }

    /// The 1-based line of byte `offset`.
    fn line(&self, offset: usize) -> usize {
        self.line_starts.partition_point(|&start| start <= offset)
    }

    /// The 0-based column of byte `offset` on its line, in characters.
    fn column(&self, offset: usize) -> usize {
        let start = self.line_starts[self.line(offset) - 1];
        self.text
            .get(start..offset)
            .map_or(0, |before| before.chars().count())
    }

    fn error(&self, offset: usize, message: impl Into<String>) -> HandFileError {
        HandFileError {
            file: self.origin.to_string(),
            line: self.line(offset),
            message: message.into(),
        }
    }

    /// Parses one formula; a parse error points at its column in the file.
    fn formula(
        &self,
        label: &str,
        value: &Spanned<Formula>,
        scope: &Scope,
    ) -> Result<Entry, HandFileError> {
        let start = value.span().start;
        let line = self.line(start);
        let text = value.get_ref().text();
        parse(&text, scope)
            .map(|expr| Entry { expr, line })
            .map_err(
                |ParseError {
                     offset,
                     mut message,
                 }| {
                    if message.starts_with("unknown name") {
                        message = format!("{message}; the model's names: {}", self.names);
                    }
                    // The formula starts one character after its opening quote.
                    let column = self.column(start) + 2;
                    HandFileError {
                        file: self.origin.to_string(),
                        line,
                        message: format!("{label}, column {}: {message}", column + offset),
                    }
                },
            )
    }

    /// The entries of a table keyed by `names`, in that order: an unknown key and a missing
    /// name are errors.
    fn vector(
        &self,
        table: &str,
        value: &Vector,
        names: &[String],
        scope: &Scope,
    ) -> Result<Vec<Entry>, HandFileError> {
        self.unknown_keys(table, value.get_ref(), names, |v| v.span().start)?;
        names
            .iter()
            .map(|name| match value.get_ref().get(name) {
                Some(f) => self.formula(&format!("{table}[{name}]"), f, scope),
                None => Err(self.error(
                    value.span().start,
                    format!("[{table}] has no entry for `{name}` (give every one: 0 if zero)"),
                )),
            })
            .collect()
    }

    /// A matrix given by rows (`w_y = ["…", "…"]`), rows and columns in the order of `names`
    /// (the model's `what`, for messages).
    fn matrix(
        &self,
        (table, what): (&str, &str),
        value: &Matrix,
        names: &[String],
        scope: &Scope,
    ) -> Result<Vec<Vec<Entry>>, HandFileError> {
        self.unknown_keys(table, value.get_ref(), names, |v| v.span().start)?;
        names
            .iter()
            .map(|row| {
                let Some(entries) = value.get_ref().get(row) else {
                    return Err(self.error(
                        value.span().start,
                        format!("[{table}] has no row `{row}` (give every row)"),
                    ));
                };
                if entries.get_ref().len() != names.len() {
                    return Err(self.error(
                        entries.span().start,
                        format!(
                            "{table}[{row}] has {} entries, the model has {} {what} ({})",
                            entries.get_ref().len(),
                            names.len(),
                            names.join(", ")
                        ),
                    ));
                }
                entries
                    .get_ref()
                    .iter()
                    .zip(names)
                    .map(|(f, col)| self.formula(&format!("{table}[{row},{col}]"), f, scope))
                    .collect()
            })
            .collect()
    }

    fn unknown_keys<V>(
        &self,
        table: &str,
        map: &BTreeMap<String, V>,
        names: &[String],
        offset: impl Fn(&V) -> usize,
    ) -> Result<(), HandFileError> {
        match map.iter().find(|(k, _)| !names.contains(k)) {
            Some((k, v)) => Err(self.error(
                offset(v),
                format!("[{table}]: `{k}` is not one of {}", names.join(", ")),
            )),
            None => Ok(()),
        }
    }
}

/// The model's state names.
fn state_names(ir: &Ir) -> Vec<String> {
    ir.states().iter().map(|s| s.name.clone()).collect()
}

/// The names formulas may use: pi and the model's parameter names, and unless `params_only`
/// (the linear form, whose matrices depend on the parameters alone) its state and input names.
fn base_scope(ir: &Ir, params_only: bool) -> Scope {
    let mut scope = Scope::new();
    scope.insert("pi".into(), Expr::Pi);
    for (i, p) in ir.params().iter().enumerate() {
        scope.insert(p.name.clone(), Expr::Var(Var::P(i)));
    }
    if params_only {
        return scope;
    }
    for (i, s) in ir.inputs().iter().enumerate() {
        scope.insert(s.name.clone(), Expr::Var(Var::U(i)));
    }
    for (i, s) in ir.states().iter().enumerate() {
        scope.insert(s.name.clone(), Expr::Var(Var::X(i)));
    }
    scope
}

/// Adds the `[let]` names in dependency order (each may use the model's names and other lets,
/// in any order in the file). Each let is parsed once, after the lets it uses: a depth-first walk
/// over the names they use, without recursion (a chain of 30,000 lets is one), which names a
/// cycle as the cycle it is.
fn add_lets(
    src: &Source<'_>,
    lets: &BTreeMap<String, Spanned<Formula>>,
    scope: &mut Scope,
) -> Result<(), HandFileError> {
    for (name, value) in lets {
        if scope.contains_key(name) {
            return Err(src.error(
                value.span().start,
                format!("[let] `{name}` is already a state, input or parameter name (or pi)"),
            ));
        }
    }
    // The other lets each let uses (a formula that does not tokenise fails when it is parsed).
    let uses: BTreeMap<&str, Vec<&str>> = lets
        .iter()
        .map(|(name, value)| {
            let used = super::parse::names_used(&value.get_ref().text()).unwrap_or_default();
            let used = used
                .iter()
                .filter_map(|u| lets.get_key_value(u.as_str()).map(|(k, _)| k.as_str()))
                .collect();
            (name.as_str(), used)
        })
        .collect();
    let mut done: std::collections::BTreeSet<&str> = Default::default();
    for root in lets.keys() {
        // The path from `root`: each let with the index of the next name it uses to visit.
        let mut path: Vec<(&str, usize)> = vec![(root.as_str(), 0)];
        while let Some(&(name, next)) = path.last() {
            if done.contains(name) {
                path.pop();
                continue;
            }
            match uses[name].get(next) {
                Some(&used) => {
                    path.last_mut().expect("on the path").1 += 1;
                    if let Some(at) = path.iter().position(|(n, _)| *n == used) {
                        let mut cycle: Vec<&str> = path[at..].iter().map(|(n, _)| *n).collect();
                        cycle.push(used);
                        return Err(src.error(
                            lets[used].span().start,
                            format!(
                                "[let] names use each other in a cycle: {}",
                                cycle.join(" → ")
                            ),
                        ));
                    }
                    if !done.contains(used) {
                        path.push((used, 0));
                    }
                }
                None => {
                    path.pop();
                    let entry = src.formula(&format!("let {name}"), &lets[name], scope)?;
                    scope.insert(name.to_string(), entry.expr);
                    done.insert(name);
                }
            }
        }
    }
    Ok(())
}

/// The speeds' state indices, if the state is the coordinates followed by the speeds.
fn mechanical_names(
    ir: &Ir,
    src: &Source<'_>,
) -> Result<(Vec<String>, Vec<String>), HandFileError> {
    let not_mechanical = || HandFileError {
        file: src.origin.to_string(),
        line: 0,
        message: format!(
            "model `{}` has no mechanics (M, Cp, F, Q): give only [f]",
            ir.model()
        ),
    };
    let mech = ir.mechanics().ok_or_else(not_mechanical)?;
    let states = state_names(ir);
    let (coords, speeds) = (mech.coordinates.clone(), mech.speeds.clone());
    let in_order = coords.iter().chain(&speeds).eq(states.iter());
    if !in_order {
        return Err(HandFileError {
            file: src.origin.to_string(),
            line: 0,
            message: format!(
                "model `{}`: its state is not its coordinates followed by its speeds; give only [f]",
                ir.model()
            ),
        });
    }
    Ok((coords, speeds))
}

/// The coordinates and rates of the steady motion's modes (its first and second half), for the
/// linear form.
fn linear_names(ir: &Ir, src: &Source<'_>) -> Result<(Vec<String>, Vec<String>), HandFileError> {
    let fail = |message: String| HandFileError {
        file: src.origin.to_string(),
        line: 0,
        message,
    };
    let motion = ir
        .mechanics()
        .and_then(|m| m.steady_motion.as_ref())
        .ok_or_else(|| {
            fail(format!(
                "model `{}` describes no steady motion (mechanics.steady_motion): the linear form \
                 needs one",
                ir.model()
            ))
        })?;
    let half = motion.modes.len() / 2;
    if motion.modes.len() % 2 != 0 || half == 0 {
        return Err(fail(format!(
            "model `{}`: its steady motion's modes ({}) are not coordinates followed by their rates",
            ir.model(),
            motion.modes.join(", ")
        )));
    }
    Ok((motion.modes[..half].to_vec(), motion.modes[half..].to_vec()))
}

/// Reads the hand file `text` (named `origin` in messages) against the model `ir`.
pub fn read_hand_file(text: &str, origin: &str, ir: &Ir) -> Result<HandModel, HandFileError> {
    let list = |names: Vec<&str>| names.join(", ");
    let src = Source::new(
        text,
        origin,
        format!(
            "states {}; inputs {}; parameters {}",
            list(ir.states().iter().map(|s| s.name.as_str()).collect()),
            list(ir.inputs().iter().map(|s| s.name.as_str()).collect()),
            list(ir.params().iter().map(|p| p.name.as_str()).collect()),
        ),
    );
    let doc: Document = toml::from_str(text).map_err(|e| src.toml_error(&e))?;
    if let Some(model) = &doc.model {
        if model.get_ref() != ir.model() {
            let model_name = model.get_ref();
            return Err(src.error(
                model.span().start,
                format!(
                    "model = \"{model_name}\", but the audited model is `{}`",
                    ir.model()
                ),
            ));
        }
    }
    let mut scope = base_scope(ir, doc.linear.is_some());
    if let Some(lets) = &doc.lets {
        add_lets(&src, lets, &mut scope)?;
    }
    let mechanical = [
        doc.mass.is_some(),
        doc.velocity.is_some(),
        doc.coriolis.is_some(),
        doc.gravity.is_some(),
        doc.inputs.is_some(),
        doc.qdot.is_some(),
    ];
    let whole_file = |message: String| HandFileError {
        file: origin.to_string(),
        line: 0,
        message,
    };
    let forms_given = [
        doc.f.is_some(),
        mechanical.iter().any(|m| *m),
        doc.linear.is_some(),
    ];
    match forms_given.iter().filter(|given| **given).count() {
        0 => {
            return Err(whole_file(
                "no equations: give [M], [Cp] or [C], [F], [Q] and [qdot], or only [f], or the \
                 linear form [linear.M], [linear.C1], [linear.K0], [linear.K2]"
                    .into(),
            ))
        }
        1 => {}
        _ => {
            return Err(whole_file(
                "give one form: [f], the mechanical form ([M], [Cp] or [C], [F], [Q], [qdot]), \
                 or the linear form ([linear.*]), not several"
                    .into(),
            ))
        }
    }
    let form = match (&doc.f, &doc.linear) {
        (None, Some(tables)) => {
            let (coordinates, rates) = linear_names(ir, &src)?;
            let missing =
                |table: &str| whole_file(format!("the linear form needs [linear.{table}]"));
            let matrix = |table: &str, value: &Option<Matrix>| {
                src.matrix(
                    (table, "coordinates in its steady motion's modes"),
                    value.as_ref().ok_or_else(|| missing(table))?,
                    &coordinates,
                    &scope,
                )
            };
            HandForm::Linear {
                mass: matrix("M", &tables.mass)?,
                c1: matrix("C1", &tables.c1)?,
                k0: matrix("K0", &tables.k0)?,
                k2: matrix("K2", &tables.k2)?,
                coordinates,
                rates,
            }
        }
        (Some(f), _) => {
            let states = state_names(ir);
            HandForm::Explicit {
                f: src.vector("f", f, &states, &scope)?,
            }
        }
        (None, None) => {
            let (coords, speeds) = mechanical_names(ir, &src)?;
            let missing = |table: &str| whole_file(format!("the mechanical form needs [{table}]"));
            let mass = src.matrix(
                ("M", "speeds"),
                doc.mass.as_ref().ok_or_else(|| missing("M"))?,
                &speeds,
                &scope,
            )?;
            let (velocity, from_coriolis_matrix) = match (&doc.velocity, &doc.coriolis) {
                (Some(_), Some(_)) => {
                    return Err(whole_file(
                        "give either [Cp] (the velocity terms) or [C] (Cp = C p), not both".into(),
                    ))
                }
                (None, None) => return Err(missing("Cp] or [C")),
                (Some(cp), None) => (src.vector("Cp", cp, &speeds, &scope)?, false),
                (None, Some(c)) => {
                    let rows = src.matrix(("C", "speeds"), c, &speeds, &scope)?;
                    (coriolis_times_speeds(rows, coords.len()), true)
                }
            };
            let vector = |table: &str, v: &Option<Vector>, names: &[String]| {
                src.vector(
                    table,
                    v.as_ref().ok_or_else(|| missing(table))?,
                    names,
                    &scope,
                )
            };
            HandForm::Mechanical {
                mass,
                velocity,
                from_coriolis_matrix,
                gravity: vector("F", &doc.gravity, &speeds)?,
                inputs: vector("Q", &doc.inputs, &speeds)?,
                qdot: vector("qdot", &doc.qdot, &coords)?,
            }
        }
    };
    Ok(HandModel {
        origin: origin.to_string(),
        model: doc.model.map(Spanned::into_inner),
        form,
    })
}

/// Cp_i = Σ_j C[i, j] p_j, the speeds p_j being the states after the `nq` coordinates.
fn coriolis_times_speeds(rows: Vec<Vec<Entry>>, nq: usize) -> Vec<Entry> {
    rows.into_iter()
        .map(|row| {
            let line = row.first().map_or(0, |e| e.line);
            let expr = row
                .into_iter()
                .enumerate()
                .map(|(j, e)| Expr::product(e.expr, Expr::Var(Var::X(nq + j))))
                .reduce(Expr::sum)
                .unwrap_or(Expr::Num(0.0));
            Entry { expr, line }
        })
        .collect()
}

/// The `model = "…"` a hand file names, read before the model is resolved (so that
/// `twv audit --hand FILE` needs no `--model`); an error if the file is not TOML.
pub fn model_named_in(text: &str, origin: &str) -> Result<Option<String>, HandFileError> {
    let src = Source::new(text, origin, String::new());
    let table: toml::Table = toml::from_str(text).map_err(|e| src.toml_error(&e))?;
    Ok(table
        .get("model")
        .and_then(|m| m.as_str())
        .map(str::to_string))
}
