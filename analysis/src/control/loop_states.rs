//! Which coordinates of a closed loop the pitch controller acts on: the smallest set that holds
//! Φ, w_y and the controller's own states and is closed under "a kept rate depends on it".
//! Its complement — the drift a pitch loop neither sees nor restores (x, y, θ, and v_x, v_y,
//! w_z without outer loops) — is then an invariant subspace of the tangent dynamics, so the
//! loop's stability is the sign of the exponents on the kept coordinates.

use twv_model::Model;

use super::field::PidLoop;
use crate::integrate::VectorField;

/// The loop's coordinates of `field`, from the dense Jacobian at the upright rest point and at
/// each of `points` (entries below 1e-12 of the largest count as zero).
pub fn loop_states<M, const NX: usize, const NU: usize, const NA: usize>(
    field: &PidLoop<'_, M, NX, NU, NA>,
    points: &[[f64; NA]],
) -> [bool; NA]
where
    M: Model<NX, NU>,
{
    let mut keep = [false; NA];
    keep[field.plant().measured.phi] = true;
    keep[field.plant().measured.w_y] = true;
    keep[NX..].iter_mut().for_each(|k| *k = true);
    let mut jacobians = Vec::with_capacity(points.len() + 1);
    for x in std::iter::once(&[0.0; NA]).chain(points) {
        let mut j = [[0.0; NA]; NA];
        field.jacobian(0.0, x, &mut j);
        jacobians.push(j);
    }
    loop {
        let mut grew = false;
        for j in &jacobians {
            let scale = j.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
            for i in 0..NA {
                if !keep[i] {
                    continue;
                }
                for c in 0..NA {
                    if !keep[c] && j[i][c].abs() > 1e-12 * scale {
                        keep[c] = true;
                        grew = true;
                    }
                }
            }
        }
        if !grew {
            return keep;
        }
    }
}
