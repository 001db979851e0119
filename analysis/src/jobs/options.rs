//! A job's flat options: the one vocabulary that the command line's flags and Python's keyword
//! arguments speak. Each option sets part of the job's settings type (whose `Default` holds every
//! default) and reads it back, so a front end shows the library's defaults and restates none.
//!
//! Options are applied in the order of the job's table, not in the order given, so a rule
//! between options (`tracking_time` needs `anti_windup = back_calculation`) is checked once,
//! here, whichever front end asked. Every option takes its typed JSON value (what Python sends)
//! or its text form (what the command line passes: `"0.1"`, `"1,2,3"`, `"study"`).

use std::collections::BTreeMap;
use std::sync::Arc;

use serde::Serialize;
use serde_json::Value;

use crate::error::{Error, Result};

/// What an option's value is (for help texts, value names and Python's documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A real number (text: `0.1`, `1e-3`, `inf`).
    Number,
    /// A whole number ≥ 0.
    Integer,
    /// On or off (the command line's flag without a value).
    Flag,
    /// Numbers in a fixed order, such as a state (text: `0.1,0,0`).
    Vector,
    /// A word from `choices`.
    Choice,
    /// Text in the option's own syntax (a setpoint `sine:0.03`, a spec `dpm>=45`, an axis
    /// `0:8000:100`), or its structured JSON value.
    Text,
}

type Setter<S> = Box<dyn Fn(&mut S, &Value) -> Result<()> + Send + Sync>;
type Getter<S> = Box<dyn Fn(&S) -> Value + Send + Sync>;

/// Where in the settings `S` a value of type `T` lives; an error when it cannot be set there
/// (a controller option of an open-loop run).
pub type Access<S, T> = Arc<dyn for<'a> Fn(&'a mut S) -> Result<&'a mut T> + Send + Sync>;

/// A field of `S`.
pub fn field<S: 'static, T: 'static>(f: fn(&mut S) -> &mut T) -> Access<S, T> {
    Arc::new(move |s| Ok(f(s)))
}

/// A field of what `outer` reaches.
pub fn sub<S: 'static, T: 'static, U: 'static>(
    outer: Access<S, T>,
    f: fn(&mut T) -> &mut U,
) -> Access<S, U> {
    Arc::new(move |s| outer(s).map(f))
}

/// One option of a job.
pub struct Opt<S> {
    /// Its name: the flag without dashes (`t_end` is `--t-end`), the Python keyword.
    pub name: &'static str,
    /// Older or shorter names it also answers to.
    pub aliases: &'static [&'static str],
    /// What its value is.
    pub kind: Kind,
    /// The words a [`Kind::Choice`] takes.
    pub choices: &'static [&'static str],
    /// Its unit (SI), empty for none.
    pub unit: &'static str,
    /// What it does, one or two sentences.
    pub help: &'static str,
    /// The job cannot run without it (it has no default).
    pub required: bool,
    /// Python may give it by position too, after the required ones (an option that was
    /// required before another could stand in for it).
    pub positional: bool,
    /// Options that cannot be given with it.
    pub conflicts: &'static [&'static str],
    /// It may be given several times (the command line's repeated flag; a list in JSON).
    pub many: bool,
    set: Setter<S>,
    get: Getter<S>,
}

/// An option as front ends see it: everything but the code, with its default.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OptionInfo {
    pub name: &'static str,
    pub aliases: &'static [&'static str],
    pub kind: Kind,
    pub choices: &'static [&'static str],
    pub unit: &'static str,
    pub help: &'static str,
    pub required: bool,
    pub positional: bool,
    pub many: bool,
    /// Its value in the job's default settings, in the option's own form (`null`: not set).
    pub default: Value,
}

impl<S: Clone + 'static> Opt<S> {
    /// An option with its own setter and getter.
    pub fn new(
        name: &'static str,
        kind: Kind,
        unit: &'static str,
        help: &'static str,
        set: impl Fn(&mut S, &Value) -> Result<()> + Send + Sync + 'static,
        get: impl Fn(&S) -> Value + Send + Sync + 'static,
    ) -> Self {
        Self {
            name,
            aliases: &[],
            kind,
            choices: &[],
            unit,
            help,
            required: false,
            positional: false,
            conflicts: &[],
            many: false,
            set: Box::new(set),
            get: Box::new(get),
        }
    }

    /// Also answers to `aliases`.
    pub fn aliases(mut self, aliases: &'static [&'static str]) -> Self {
        self.aliases = aliases;
        self
    }

    /// Has no default: the job needs it.
    pub fn required(mut self) -> Self {
        self.required = true;
        self
    }

    /// May be given by position in Python (see [`Opt::positional`]'s field).
    pub fn positional(mut self) -> Self {
        self.positional = true;
        self
    }

    /// May be given several times.
    pub fn many(mut self) -> Self {
        self.many = true;
        self
    }

    /// Cannot be given with `others`.
    pub fn conflicts(mut self, others: &'static [&'static str]) -> Self {
        self.conflicts = others;
        self
    }

    /// Takes one of `choices`.
    pub fn choices(mut self, choices: &'static [&'static str]) -> Self {
        self.kind = Kind::Choice;
        self.choices = choices;
        self
    }

    /// Whether `name` is this option.
    pub fn answers_to(&self, name: &str) -> bool {
        self.name == name || self.aliases.contains(&name)
    }

    /// The option's value in `settings`.
    pub fn get(&self, settings: &S) -> Value {
        (self.get)(settings)
    }

    /// Sets the option in `settings`.
    pub fn set(&self, settings: &mut S, value: &Value) -> Result<()> {
        (self.set)(settings, value)
    }

    /// The option as front ends see it, with its value in `defaults`.
    pub fn info(&self, defaults: &S) -> OptionInfo {
        OptionInfo {
            name: self.name,
            aliases: self.aliases,
            kind: self.kind,
            choices: self.choices,
            unit: self.unit,
            help: self.help,
            required: self.required,
            positional: self.positional,
            many: self.many,
            default: self.get(defaults),
        }
    }
}

/// The value `access` reaches in a copy of `settings` (null where it cannot be reached).
fn read<S: Clone, T: Serialize>(access: &Access<S, T>, settings: &S) -> Value {
    let mut copy = settings.clone();
    match access(&mut copy) {
        Ok(v) => serde_json::to_value(&*v).unwrap_or(Value::Null),
        Err(_) => Value::Null,
    }
}

/// A number as an option's value: JSON cannot hold infinity, so it is the text `inf`.
pub fn number_value(x: f64) -> Value {
    if x.is_finite() {
        Value::from(x)
    } else {
        Value::String(x.to_string())
    }
}

/// A number option.
pub fn number<S: Clone + 'static>(
    name: &'static str,
    unit: &'static str,
    help: &'static str,
    access: Access<S, f64>,
) -> Opt<S> {
    let get = access.clone();
    Opt::new(
        name,
        Kind::Number,
        unit,
        help,
        move |s, v| {
            let x = as_number(name, v)?;
            *access(s)? = x;
            Ok(())
        },
        move |s| read(&get, s),
    )
}

/// A number option that may be unset (`null`, or `none` on the command line).
pub fn optional_number<S: Clone + 'static>(
    name: &'static str,
    unit: &'static str,
    help: &'static str,
    access: Access<S, Option<f64>>,
) -> Opt<S> {
    let get = access.clone();
    Opt::new(
        name,
        Kind::Number,
        unit,
        help,
        move |s, v| {
            let x = if is_none(v) {
                None
            } else {
                Some(as_number(name, v)?)
            };
            *access(s)? = x;
            Ok(())
        },
        move |s| read(&get, s),
    )
}

/// A whole-number option.
pub fn integer<S: Clone + 'static>(
    name: &'static str,
    unit: &'static str,
    help: &'static str,
    access: Access<S, usize>,
) -> Opt<S> {
    let get = access.clone();
    Opt::new(
        name,
        Kind::Integer,
        unit,
        help,
        move |s, v| {
            let n = as_integer(name, v)?;
            *access(s)? =
                usize::try_from(n).map_err(|_| Error::input(name, format!("{n} is too large")))?;
            Ok(())
        },
        move |s| read(&get, s),
    )
}

/// An on/off option.
pub fn flag<S: Clone + 'static>(
    name: &'static str,
    help: &'static str,
    access: Access<S, bool>,
) -> Opt<S> {
    let get = access.clone();
    Opt::new(
        name,
        Kind::Flag,
        "",
        help,
        move |s, v| {
            *access(s)? = as_bool(name, v)?;
            Ok(())
        },
        move |s| read(&get, s),
    )
}

/// A vector option that may be unset.
pub fn optional_vector<S: Clone + 'static>(
    name: &'static str,
    unit: &'static str,
    help: &'static str,
    access: Access<S, Option<Vec<f64>>>,
) -> Opt<S> {
    let get = access.clone();
    Opt::new(
        name,
        Kind::Vector,
        unit,
        help,
        move |s, v| {
            *access(s)? = if is_none(v) {
                None
            } else {
                Some(as_vector(name, v)?)
            };
            Ok(())
        },
        move |s| read(&get, s),
    )
}

/// A vector option (empty, shown as not set, until given).
pub fn vector<S: Clone + 'static>(
    name: &'static str,
    unit: &'static str,
    help: &'static str,
    access: Access<S, Vec<f64>>,
) -> Opt<S> {
    let get = access.clone();
    Opt::new(
        name,
        Kind::Vector,
        unit,
        help,
        move |s, v| {
            *access(s)? = as_vector(name, v)?;
            Ok(())
        },
        move |s| match read(&get, s) {
            Value::Array(a) if a.is_empty() => Value::Null,
            other => other,
        },
    )
}

/// Whether `v` means "not set": JSON null, or `none` on the command line.
pub fn is_none(v: &Value) -> bool {
    match v {
        Value::Null => true,
        Value::String(s) => s.trim().eq_ignore_ascii_case("none"),
        _ => false,
    }
}

/// `v` as a number: a JSON number, or text such as `0.1`, `1e-3`, `inf`.
pub fn as_number(name: &str, v: &Value) -> Result<f64> {
    match v {
        Value::Number(n) => n
            .as_f64()
            .ok_or_else(|| Error::input(name, format!("{n} is not a number"))),
        Value::String(s) => s
            .trim()
            .parse::<f64>()
            .map_err(|_| Error::input(name, format!("`{}` is not a number", s.trim()))),
        other => Err(Error::input(
            name,
            format!("wants a number, not {}", describe(other)),
        )),
    }
}

/// `v` as a whole number ≥ 0.
pub fn as_integer(name: &str, v: &Value) -> Result<u64> {
    let bad = |what: String| Error::input(name, format!("{what} is not a whole number ≥ 0"));
    match v {
        Value::Number(n) => n.as_u64().ok_or_else(|| bad(n.to_string())),
        Value::String(s) => s
            .trim()
            .parse::<u64>()
            .map_err(|_| bad(format!("`{}`", s.trim()))),
        other => Err(bad(describe(other))),
    }
}

/// `v` as on/off: a JSON boolean, or `true`/`false`.
pub fn as_bool(name: &str, v: &Value) -> Result<bool> {
    match v {
        Value::Bool(b) => Ok(*b),
        Value::String(s) if s.trim() == "true" => Ok(true),
        Value::String(s) if s.trim() == "false" => Ok(false),
        other => Err(Error::input(
            name,
            format!("wants true or false, not {}", describe(other)),
        )),
    }
}

/// `v` as text.
pub fn as_text<'v>(name: &str, v: &'v Value) -> Result<&'v str> {
    match v {
        Value::String(s) => Ok(s.as_str()),
        other => Err(Error::input(
            name,
            format!("wants text, not {}", describe(other)),
        )),
    }
}

/// `v` as numbers in order: a JSON array, or comma-separated text (`0.1,0,0`).
pub fn as_vector(name: &str, v: &Value) -> Result<Vec<f64>> {
    match v {
        Value::Array(items) => items.iter().map(|x| as_number(name, x)).collect(),
        Value::String(s) if s.trim().is_empty() => Ok(Vec::new()),
        Value::String(s) => s
            .split(',')
            .map(|part| as_number(name, &Value::String(part.to_string())))
            .collect(),
        other => Err(Error::input(
            name,
            format!("wants numbers, not {}", describe(other)),
        )),
    }
}

/// `v` as several vectors: a JSON array of arrays, or `a,b;c,d` on the command line.
pub fn as_vectors(name: &str, v: &Value) -> Result<Vec<Vec<f64>>> {
    match v {
        Value::Array(items) => items.iter().map(|x| as_vector(name, x)).collect(),
        Value::String(s) => s
            .split(';')
            .map(str::trim)
            .filter(|p| !p.is_empty())
            .map(|part| as_vector(name, &Value::String(part.to_string())))
            .collect(),
        other => Err(Error::input(
            name,
            format!("wants sets of numbers, not {}", describe(other)),
        )),
    }
}

/// `v` as named numbers: a JSON object, or `a=1,b=-2` on the command line.
pub fn as_named(name: &str, v: &Value) -> Result<BTreeMap<String, f64>> {
    let mut out = BTreeMap::new();
    match v {
        Value::Object(map) => {
            for (k, x) in map {
                out.insert(k.clone(), as_number(&format!("{name}.{k}"), x)?);
            }
        }
        Value::String(s) => {
            for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
                let (key, value) = part
                    .split_once('=')
                    .ok_or_else(|| Error::input(name, format!("`{part}` is not NAME=VALUE")))?;
                let x = as_number(name, &Value::String(value.to_string()))?;
                if out.insert(key.trim().to_string(), x).is_some() {
                    return Err(Error::input(
                        name,
                        format!("`{}` is given twice", key.trim()),
                    ));
                }
            }
        }
        other => {
            return Err(Error::input(
                name,
                format!("wants NAME=VALUE pairs, not {}", describe(other)),
            ))
        }
    }
    Ok(out)
}

/// `v` as one of `choices` (`-` and `_` are the same).
pub fn as_choice(name: &str, v: &Value, choices: &[&'static str]) -> Result<&'static str> {
    let text = as_text(name, v)?.trim().replace('-', "_");
    choices
        .iter()
        .find(|c| c.replace('-', "_") == text)
        .copied()
        .ok_or_else(|| {
            Error::input(
                name,
                format!("`{text}` is not one of {}", choices.join(", ")),
            )
        })
}

fn describe(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("`{s}`"),
        Value::Array(_) => "a list".into(),
        Value::Object(_) => "an object".into(),
    }
}

/// Applies `given` (option name or alias, value) to `settings` in the order of `options`: an
/// unknown or repeated option is an error naming it.
pub fn apply<S: Clone + 'static>(
    job: &str,
    options: &[Opt<S>],
    settings: &mut S,
    given: &[(String, Value)],
) -> Result<()> {
    let mut slots: Vec<Option<&Value>> = vec![None; options.len()];
    for (name, value) in given {
        let key = name.replace('-', "_");
        let Some(i) = options.iter().position(|o| o.answers_to(&key)) else {
            let known: Vec<&str> = options.iter().map(|o| o.name).collect();
            return Err(Error::input(
                key,
                format!(
                    "{job} has no such option; its options: {}",
                    known.join(", ")
                ),
            ));
        };
        if slots[i].replace(value).is_some() {
            return Err(Error::input(options[i].name, "is given twice"));
        }
    }
    for (option, value) in options.iter().zip(&slots) {
        if value.is_none() {
            continue;
        }
        for other in option.conflicts {
            let given = options
                .iter()
                .zip(&slots)
                .any(|(o, v)| o.name == *other && v.is_some());
            if given {
                return Err(Error::input(
                    option.name,
                    format!("cannot be given with {other}: give one of them"),
                ));
            }
        }
    }
    for (option, value) in options.iter().zip(slots) {
        if let Some(value) = value {
            option.set(settings, value)?;
        } else if option.required {
            return Err(Error::input(option.name, format!("{job} needs it")));
        }
    }
    Ok(())
}

/// A value as the command line writes it (help texts, the docs' option tables): numbers and
/// words as they are, lists with commas, lists of lists with `;`, named values as `name=value`.
pub fn display(v: &Value) -> String {
    match v {
        Value::Null => "none".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => match n.as_f64() {
            Some(x) if x.fract() == 0.0 && x.abs() < 1e15 => format!("{}", x as i64),
            Some(x) => format!("{x:?}"),
            None => n.to_string(),
        },
        Value::String(s) if s.is_empty() => "\"\"".into(),
        Value::String(s) => s.clone(),
        Value::Array(items) if items.iter().all(|i| i.is_array() || i.is_object()) => {
            items.iter().map(display).collect::<Vec<_>>().join(";")
        }
        Value::Array(items) => items.iter().map(display).collect::<Vec<_>>().join(","),
        Value::Object(map) if ["kp", "ki", "kd"].iter().all(|k| map.contains_key(*k)) => {
            ["kp", "ki", "kd"]
                .iter()
                .map(|k| format!("{k}={}", display(&map[*k])))
                .collect::<Vec<_>>()
                .join(",")
        }
        Value::Object(map) => map
            .iter()
            .map(|(k, v)| format!("{k}={}", display(v)))
            .collect::<Vec<_>>()
            .join(","),
    }
}
