//! Householder QR of the tangent basis on fixed-size arrays.

/// Replaces the `K` vectors `w[k]` (the columns of an N × K matrix W) by the first `K` columns
/// of Q in W = QR, with the signs fixed so that R has a positive diagonal, and returns that
/// diagonal R_kk = |R_kk| ≥ 0.
///
/// Householder rather than Gram–Schmidt because the columns of W become nearly parallel between
/// re-orthonormalisations (all align with the most expanding direction); Householder's Q is
/// orthonormal to round-off regardless of that conditioning. R_kk = 0 means the vectors were
/// linearly dependent; the caller decides what that means. No allocation: everything is on the
/// stack, O(N K²) flops.
pub fn orthonormalize<const N: usize, const K: usize>(w: &mut [[f64; N]; K]) -> [f64; K] {
    // v[j] holds column j as it is reduced; rows ≥ j of v[j] end up as the j-th reflector.
    let mut v = *w;
    let mut beta = [0.0; K];
    let mut r = [0.0; K];
    for j in 0..K.min(N) {
        let (head, tail) = v.split_at_mut(j + 1);
        let col = &mut head[j];
        let norm = col[j..].iter().map(|a| a * a).sum::<f64>().sqrt();
        if norm == 0.0 {
            continue;
        }
        // α = −sign(a_j)‖a‖ avoids cancellation in v = a − α e_j; then H a = α e_j.
        let aj = col[j];
        let alpha = if aj >= 0.0 { -norm } else { norm };
        col[j] = aj - alpha;
        // ‖v‖² = 2‖a‖(‖a‖ + |a_j|).
        beta[j] = 1.0 / (norm * (norm + aj.abs()));
        r[j] = alpha;
        for c in tail.iter_mut() {
            reflect(&col[j..], beta[j], &mut c[j..]);
        }
    }
    // Q e_c = H_0 ⋯ H_c e_c (reflectors after c leave e_c alone), sign-flipped so R_cc > 0.
    for (c, wc) in w.iter_mut().enumerate() {
        let mut q = [0.0; N];
        if c < N {
            q[c] = 1.0;
        }
        for j in (0..=c.min(N.saturating_sub(1))).rev() {
            if beta[j] != 0.0 {
                reflect(&v[j][j..], beta[j], &mut q[j..]);
            }
        }
        if r[c] < 0.0 {
            for qi in q.iter_mut() {
                *qi = -*qi;
            }
        }
        *wc = q;
    }
    r.map(f64::abs)
}

/// x ← (I − β v vᵀ) x on equally long slices.
#[inline(always)]
fn reflect(v: &[f64], beta: f64, x: &mut [f64]) {
    let d: f64 = v.iter().zip(x.iter()).map(|(a, b)| a * b).sum();
    let s = beta * d;
    for (xi, vi) in x.iter_mut().zip(v.iter()) {
        *xi -= s * vi;
    }
}
