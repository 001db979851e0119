//! Seeded audit samples: not only near upright but at large angles, fast spins and large inputs,
//! where a wrong term cannot hide behind small factors.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A state and input at which two models are compared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample<const NX: usize, const NU: usize> {
    pub x: [f64; NX],
    pub u: [f64; NU],
}

/// Range of a state by its name: angles anywhere, positions and speeds large.
fn half_range(name: &str) -> f64 {
    match name {
        "phi" | "theta" => std::f64::consts::PI,
        "x" | "y" => 20.0,
        "w_z" => 8.0,
        "w_y" => 6.0,
        _ => 5.0,
    }
}

/// `n` samples from `seed`: first the upright at rest and the hanging rest state, then random.
pub fn samples<const NX: usize, const NU: usize>(
    state_names: &[&str],
    input_scale: f64,
    n: usize,
    seed: u64,
) -> Vec<Sample<NX, NU>> {
    sample_vectors(state_names, NU, input_scale, n, seed)
        .into_iter()
        .map(|(x, u)| Sample {
            x: x.try_into().expect("NX states"),
            u: u.try_into().expect("NU inputs"),
        })
        .collect()
}

/// [`samples`] with run-time sizes, as (x, u) pairs: the same numbers for the same sizes.
pub fn sample_vectors<S: AsRef<str>>(
    state_names: &[S],
    nu: usize,
    input_scale: f64,
    n: usize,
    seed: u64,
) -> Vec<(Vec<f64>, Vec<f64>)> {
    let nx = state_names.len();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    let mut hanging = vec![0.0; nx];
    if let Some(first) = hanging.first_mut() {
        *first = std::f64::consts::PI;
    }
    for x in [vec![0.0; nx], hanging].into_iter().take(n) {
        out.push((x, vec![0.0; nu]));
    }
    while out.len() < n {
        let x = state_names
            .iter()
            .map(|name| {
                let r = half_range(name.as_ref());
                rng.gen_range(-r..r)
            })
            .collect();
        // A zero scale gives zero inputs (an empty range would panic).
        let u = (0..nu)
            .map(|_| match input_scale > 0.0 {
                true => rng.gen_range(-input_scale..input_scale),
                false => 0.0,
            })
            .collect();
        out.push((x, u));
    }
    out
}
