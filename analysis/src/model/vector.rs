//! Checked state and input vectors: the right length for the model and finite, named in the
//! error by the setting they came from.

use crate::error::{Error, Result};

/// `values` as a state of `names.len()` components (`N` of them, the const size): the length
/// must match and every value be finite.
pub fn state_vector<const N: usize>(
    field: &str,
    values: &[f64],
    names: &[&str],
) -> Result<[f64; N]> {
    let v = checked(field, values, names)?;
    let mut out = [0.0; N];
    out.iter_mut().zip(v).for_each(|(o, x)| *o = *x);
    Ok(out)
}

/// `values` as an input of the model's `names.len()` inputs, padded with zeros to `N` (an
/// interpreted model may carry padding inputs after its own).
pub fn input_vector<const N: usize>(
    field: &str,
    values: &[f64],
    names: &[&str],
) -> Result<[f64; N]> {
    state_vector(field, values, names)
}

/// Checks that `values` has one finite value per name.
pub fn check_vector(field: &str, values: &[f64], names: &[&str]) -> Result<()> {
    checked(field, values, names).map(|_| ())
}

fn checked<'a>(field: &str, values: &'a [f64], names: &[&str]) -> Result<&'a [f64]> {
    if values.len() != names.len() {
        return Err(Error::input(
            field,
            format!(
                "{} values, the model has {} ({})",
                values.len(),
                names.len(),
                names.join(", ")
            ),
        ));
    }
    if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(Error::input(
            field,
            format!("{} = {v} is not finite", names[i]),
        ));
    }
    Ok(values)
}
