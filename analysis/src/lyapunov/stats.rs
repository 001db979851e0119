//! Statistics of the finite-time exponents: batch-means standard errors and the Kaplan–Yorke
//! dimension.

/// Standard error of the mean of `samples` (per-interval local exponents, in time order) by
/// batch means: the last `batches · ⌊n / batches⌋` samples are cut into `batches` consecutive
/// batches, and the error is the standard deviation of the batch means over √batches.
///
/// Local exponents of consecutive intervals are strongly correlated, so the naive σ/√n would
/// understate the error; batches much longer than the correlation time are nearly independent.
/// Any leftover samples are dropped from the start (the least converged end). Returns NaN if
/// fewer than 2 batches of at least one sample are possible.
pub fn batch_means_stderr(samples: &[f64], batches: usize) -> f64 {
    if batches < 2 || samples.len() < batches {
        return f64::NAN;
    }
    let m = samples.len() / batches;
    let used = &samples[samples.len() - m * batches..];
    let means: Vec<f64> = used
        .chunks_exact(m)
        .map(|c| c.iter().sum::<f64>() / m as f64)
        .collect();
    stderr_of_batch_means(&means)
}

/// The standard error of the overall mean from the means of equal batches: their standard
/// deviation over √(number of batches); NaN for fewer than two batches.
pub fn stderr_of_batch_means(means: &[f64]) -> f64 {
    if means.len() < 2 {
        return f64::NAN;
    }
    let b = means.len() as f64;
    let mean = means.iter().sum::<f64>() / b;
    let var = means.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (b - 1.0);
    (var / b).sqrt()
}

/// The Kaplan–Yorke (Lyapunov) dimension D = j + (λ_1 + … + λ_j)/|λ_{j+1}| of a spectrum sorted
/// in descending order, j the largest index with a non-negative partial sum.
///
/// `full` says whether `sorted` is the whole spectrum. D = 0 if λ_1 < 0; if every partial sum
/// is non-negative, D is the dimension N for a full spectrum (volume is not contracted) and
/// unknown (`None`) for a partial one, which cannot tell where the sum turns negative.
pub fn kaplan_yorke(sorted: &[f64], full: bool) -> Option<f64> {
    let mut sum = 0.0;
    for (j, &l) in sorted.iter().enumerate() {
        if sum + l < 0.0 {
            return Some(j as f64 + sum / l.abs());
        }
        sum += l;
    }
    full.then_some(sorted.len() as f64)
}
