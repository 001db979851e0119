//! Parameter files: a TOML table read into values in the IR's parameter order, using each
//! parameter's `key` and `index`, and validated by its `kind` (see generated/ir/README.md).
//! An optional `[uncertainty]` table gives one standard deviation per key (the same shape as
//! its value): it is not a value, and [`parse_uncertainty`] reads it for Monte Carlo runs.

use std::path::Path;

use toml::{Table, Value};

use crate::error::{ParamError, ParamProblem};
use crate::types::{Param, ParamKind};

/// Read the TOML file at `path` into values in the order of `params`.
pub fn load_params(path: impl AsRef<Path>, params: &[Param]) -> Result<Vec<f64>, ParamError> {
    let path = path.as_ref();
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| ParamError {
        file: file.clone(),
        problem: ParamProblem::Io(e.to_string()),
    })?;
    parse_params(&text, &file, params)
}

/// Parse TOML text into values in the order of `params`; `file` is the name used in errors.
pub fn parse_params(text: &str, file: &str, params: &[Param]) -> Result<Vec<f64>, ParamError> {
    parse_inner(text, params).map_err(|problem| ParamError {
        file: file.to_string(),
        problem,
    })
}

/// Check values given directly (not from a file) the way a file's values are checked.
pub fn check_values(values: &[f64], file: &str, params: &[Param]) -> Result<(), ParamError> {
    check_all(values, params).map_err(|problem| ParamError {
        file: file.to_string(),
        problem,
    })
}

/// The key of the standard deviations' table.
pub const UNCERTAINTY: &str = "uncertainty";

/// The standard deviation of each parameter (IR order; 0 where the file gives none) from the
/// `[uncertainty]` table of a parameter file's text, checked: known keys, the value's shape,
/// finite and ≥ 0. The values themselves are checked too (the file must be a valid file).
pub fn parse_uncertainty(text: &str, file: &str, params: &[Param]) -> Result<Vec<f64>, ParamError> {
    let err = |problem| ParamError {
        file: file.to_string(),
        problem,
    };
    let (table, _) = read_table(text, params).map_err(err)?;
    uncertainty_of(&table, params).map_err(err)
}

/// The TOML table of a parameter file and its values, checked.
fn read_table(text: &str, params: &[Param]) -> Result<(Table, Vec<f64>), ParamProblem> {
    let table: Table = text
        .parse()
        .map_err(|e: toml::de::Error| ParamProblem::Syntax(e.to_string().trim().to_string()))?;
    if let Some(key) = table
        .keys()
        .find(|k| *k != UNCERTAINTY && !params.iter().any(|p| &p.key == *k))
    {
        return Err(ParamProblem::UnknownKey(key.clone()));
    }
    let values = params
        .iter()
        .map(|p| value_of(&table, p, params))
        .collect::<Result<Vec<_>, _>>()?;
    check_all(&values, params)?;
    uncertainty_of(&table, params)?;
    Ok((table, values))
}

fn parse_inner(text: &str, params: &[Param]) -> Result<Vec<f64>, ParamProblem> {
    read_table(text, params).map(|(_, values)| values)
}

/// The `[uncertainty]` table's standard deviations in IR order (0 where absent).
fn uncertainty_of(table: &Table, params: &[Param]) -> Result<Vec<f64>, ParamProblem> {
    let Some(raw) = table.get(UNCERTAINTY) else {
        return Ok(vec![0.0; params.len()]);
    };
    let Value::Table(stds) = raw else {
        return Err(ParamProblem::WrongType {
            field: UNCERTAINTY.into(),
            expected: "a table of standard deviations, [uncertainty]".into(),
            value: describe(raw),
        });
    };
    if let Some(key) = stds.keys().find(|k| !params.iter().any(|p| &p.key == *k)) {
        return Err(ParamProblem::UnknownKey(format!("{UNCERTAINTY}.{key}")));
    }
    params
        .iter()
        .map(|p| {
            if !stds.contains_key(&p.key) {
                return Ok(0.0);
            }
            let std = value_of(stds, p, params).map_err(|e| match e {
                ParamProblem::WrongType {
                    field,
                    expected,
                    value,
                } => ParamProblem::WrongType {
                    field: format!("{UNCERTAINTY}.{field}"),
                    expected,
                    value,
                },
                other => other,
            })?;
            if !(std.is_finite() && std >= 0.0) {
                return Err(ParamProblem::WrongType {
                    field: format!("{UNCERTAINTY}.{}", p.name),
                    expected: "a standard deviation, finite and ≥ 0".into(),
                    value: format!("{std}"),
                });
            }
            Ok(std)
        })
        .collect()
}

fn value_of(table: &Table, p: &Param, params: &[Param]) -> Result<f64, ParamProblem> {
    let raw = table.get(&p.key).ok_or_else(|| ParamProblem::MissingKey {
        key: p.key.clone(),
        description: p.description.clone(),
    })?;
    let Some(index) = p.index else {
        return number(raw, &p.key);
    };
    let len = params.iter().filter(|q| q.key == p.key).count();
    match raw {
        Value::Array(items) if items.len() == len => number(&items[index], &p.name),
        other => Err(ParamProblem::WrongType {
            field: p.key.clone(),
            expected: format!("an array of {len} numbers"),
            value: describe(other),
        }),
    }
}

fn number(v: &Value, field: &str) -> Result<f64, ParamProblem> {
    match v {
        Value::Float(x) => Ok(*x),
        Value::Integer(i) => Ok(*i as f64),
        other => Err(ParamProblem::WrongType {
            field: field.to_string(),
            expected: "a number".into(),
            value: describe(other),
        }),
    }
}

fn check_all(values: &[f64], params: &[Param]) -> Result<(), ParamProblem> {
    if values.len() != params.len() {
        return Err(ParamProblem::Count {
            expected: params.len(),
            given: values.len(),
        });
    }
    for (p, &value) in params.iter().zip(values) {
        check_one(p, value)?;
    }
    check_triangles(values, params)
}

fn check_one(p: &Param, value: f64) -> Result<(), ParamProblem> {
    let field = p.name.clone();
    if !value.is_finite() {
        return Err(ParamProblem::NonFinite { field, value });
    }
    if p.kind.must_be_positive() && value <= 0.0 {
        return Err(ParamProblem::NotPositive {
            field,
            kind: p.kind.name().into(),
            value,
        });
    }
    let (lo, hi) = p.kind.magnitude_range();
    let magnitude = value.abs();
    if magnitude > hi || (magnitude < lo && value != 0.0) {
        return Err(ParamProblem::Magnitude {
            field,
            kind: p.kind.name().into(),
            value,
            lo,
            hi,
        });
    }
    Ok(())
}

/// Principal inertias of one body must satisfy I_a ≤ I_b + I_c for every component: otherwise
/// no mass distribution has them.
fn check_triangles(values: &[f64], params: &[Param]) -> Result<(), ParamProblem> {
    let inertia_keys = params
        .iter()
        .filter(|p| p.kind == ParamKind::Inertia && p.index.is_some())
        .map(|p| &p.key);
    for key in inertia_keys {
        let mut triple: Vec<(usize, f64)> = params
            .iter()
            .zip(values)
            .filter(|(p, _)| &p.key == key)
            .filter_map(|(p, &v)| p.index.map(|i| (i, v)))
            .collect();
        triple.sort_by_key(|&(i, _)| i);
        let comps: Vec<f64> = triple.into_iter().map(|(_, v)| v).collect();
        let [a, b, c] = comps[..] else { continue };
        let others = [b + c, a + c, a + b];
        if let Some(index) = (0..3).find(|&i| comps[i] > others[i]) {
            return Err(ParamProblem::Triangle {
                key: key.clone(),
                values: comps.clone(),
                index,
                value: comps[index],
            });
        }
    }
    Ok(())
}

/// A short, readable rendering of a TOML value for error messages.
fn describe(v: &Value) -> String {
    match v {
        Value::String(s) => format!("{s:?}"),
        Value::Boolean(b) => b.to_string(),
        Value::Array(items) => format!("an array of {} items", items.len()),
        other => other.type_str().to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::validate::parse_ir;

    const WHIPPLE: &str = include_str!("../../../generated/ir/whipple.json");
    const BROWSER: &str = include_str!("../../../vehicles/bicycles/browser.toml");

    /// A measured bicycle's file: its values read as ever, its standard deviations in IR order.
    #[test]
    fn the_uncertainty_table_is_read_and_is_not_a_value() {
        let ir = parse_ir(WHIPPLE, "whipple.json").unwrap();
        let values = parse_params(BROWSER, "browser.toml", ir.params()).unwrap();
        let stds = parse_uncertainty(BROWSER, "browser.toml", ir.params()).unwrap();
        let at = |name: &str| ir.params().iter().position(|p| p.name == name).unwrap();
        assert_eq!(values[at("w")], 1.121);
        assert_eq!(stds[at("w")], 0.002);
        assert_eq!(stds[at("lambda")], 0.00349065850399);
        // A file without the table: every value exact.
        let plain = BROWSER.split("\n[uncertainty]\n").next().unwrap();
        let zero = parse_uncertainty(plain, "plain.toml", ir.params()).unwrap();
        assert!(zero.iter().all(|s| *s == 0.0));
    }

    /// Every mistake in the table is named: an unknown key, a negative or non-finite standard
    /// deviation, a value that is not a number, a table that is not one.
    #[test]
    fn a_bad_uncertainty_table_is_named() {
        let ir = parse_ir(WHIPPLE, "whipple.json").unwrap();
        let plain = BROWSER.split("\n[uncertainty]\n").next().unwrap();
        for (table, names) in [
            ("[uncertainty]\nwheel = 0.1\n", "uncertainty.wheel"),
            ("[uncertainty]\nw = -0.1\n", "uncertainty.w"),
            ("[uncertainty]\nw = nan\n", "uncertainty.w"),
            ("[uncertainty]\nw = \"small\"\n", "uncertainty.w"),
            ("uncertainty = 0.1\n", "uncertainty"),
        ] {
            // A plain key goes before the file's values, a table after them.
            let text = if table.starts_with('[') {
                format!("{plain}{table}")
            } else {
                format!("{table}{plain}")
            };
            let err = parse_params(&text, "bike.toml", ir.params()).unwrap_err();
            assert!(err.to_string().contains(names), "{table}: {err}");
        }
    }
}
