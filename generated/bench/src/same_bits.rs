//! The check a benchmark makes before its numbers mean anything across builds: every build of
//! the kernels performs the same IEEE operations in the same order, so a whole computation run
//! on each build this CPU has (the study's Lyapunov preset) must give the same bits.

/// One run per build: the build's name and its result (or why the run failed).
pub type Run<'a> = (&'a str, Result<Vec<f64>, String>);

/// The line to print when every run succeeded with the bits of the first; otherwise the line
/// naming the first failure or difference (a failed check: the bench exits non-zero).
pub fn same_bits(what: &str, runs: &[Run]) -> Result<String, String> {
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let mut first: Option<(&str, &Vec<f64>)> = None;
    for (build, result) in runs {
        match (result, first) {
            (Err(e), _) => return Err(format!("{what} FAILED on the {build} build: {e}")),
            (Ok(v), None) => first = Some((build, v)),
            (Ok(v), Some((name, reference))) if bits(v) != bits(reference) => {
                return Err(format!(
                    "{what} DIFFERS between the {name} and {build} builds: {reference:?} vs {v:?}"
                ))
            }
            (Ok(_), Some(_)) => {}
        }
    }
    if first.is_none() {
        return Err(format!("{what}: no build ran"));
    }
    let names: Vec<&str> = runs.iter().map(|(name, _)| *name).collect();
    Ok(format!(
        "{what}: the same bits on every build run here ({})",
        names.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::same_bits;

    #[test]
    fn equal_bits_pass_and_name_the_builds() {
        let runs = [
            ("AVX-512", Ok(vec![0.5, -0.0])),
            ("AVX2", Ok(vec![0.5, -0.0])),
        ];
        assert_eq!(
            same_bits("λ", &runs).unwrap(),
            "λ: the same bits on every build run here (AVX-512, AVX2)"
        );
    }

    #[test]
    fn one_ulp_or_a_signed_zero_fails() {
        let next = f64::from_bits(0.5f64.to_bits() + 1);
        let ulp = [("AVX-512", Ok(vec![0.5])), ("baseline", Ok(vec![next]))];
        assert!(same_bits("λ", &ulp)
            .unwrap_err()
            .contains("DIFFERS between the AVX-512 and baseline"));
        let zero = [("AVX-512", Ok(vec![0.0])), ("AVX2", Ok(vec![-0.0]))];
        assert!(same_bits("λ", &zero).is_err());
    }

    #[test]
    fn a_failed_run_or_no_run_fails() {
        let failed = [("AVX2", Err("blew up".to_string()))];
        assert!(same_bits("λ", &failed)
            .unwrap_err()
            .contains("FAILED on the AVX2 build: blew up"));
        assert!(same_bits("λ", &[]).is_err());
    }
}
