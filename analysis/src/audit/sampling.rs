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
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    let mut hanging = [0.0; NX];
    hanging[0] = std::f64::consts::PI;
    for x in [[0.0; NX], hanging].into_iter().take(n) {
        out.push(Sample { x, u: [0.0; NU] });
    }
    while out.len() < n {
        let mut x = [0.0; NX];
        for (xi, name) in x.iter_mut().zip(state_names) {
            let r = half_range(name);
            *xi = rng.gen_range(-r..r);
        }
        let mut u = [0.0; NU];
        for ui in &mut u {
            *ui = rng.gen_range(-input_scale..input_scale);
        }
        out.push(Sample { x, u });
    }
    out
}
