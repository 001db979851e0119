//! The initial tangent basis.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{orthonormalize, InitialBasis};

/// The `K` initial tangent vectors in `N` dimensions: unit vectors, or Gaussian vectors from a
/// seeded ChaCha8 stream orthonormalised by QR (with R_kk > 0 that is a Haar-random
/// orthonormal frame). Requires `K ≤ N`.
pub fn initial_basis<const N: usize, const K: usize>(basis: &InitialBasis) -> [[f64; N]; K] {
    let mut w = [[0.0; N]; K];
    match *basis {
        InitialBasis::Identity => {
            for (k, row) in w.iter_mut().enumerate() {
                if k < N {
                    row[k] = 1.0;
                }
            }
        }
        InitialBasis::Random { seed } => {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            for row in w.iter_mut() {
                for v in row.iter_mut() {
                    *v = gaussian(&mut rng);
                }
            }
            orthonormalize(&mut w);
        }
    }
    w
}

/// A standard normal sample (Box–Muller), so no distribution crate is needed.
fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    // u1 in (0, 1] keeps the logarithm finite.
    let u1: f64 = 1.0 - rng.gen::<f64>();
    let u2: f64 = rng.gen();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}
