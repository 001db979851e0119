//! `L` points of the variational system with one tangent vector each, kept as lane arrays
//! (`x[i][l]`: entry `i` of point `l`), and the RK4 step over them: the maps' form. Laid out
//! this way the stage combinations, the laws and the lanes kernel's arguments are whole lane
//! arrays (one vector instruction per entry for all points) instead of eight transposes per
//! stage between one array per point and one per entry.
//!
//! Per point the step performs exactly the operations of [`Rk4`](super::Rk4)'s step on a
//! [`VarState`] in the same order, so a point has the same bits in either form, whatever the
//! other lanes hold.

use super::VarState;

/// `L` points `x` with one tangent vector `w` each, entry `i` of point `l` at `[i][l]`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct LaneStates<const N: usize, const L: usize> {
    /// The states.
    pub x: [[f64; L]; N],
    /// The tangent vectors.
    pub w: [[f64; L]; N],
}

impl<const N: usize, const L: usize> LaneStates<N, L> {
    /// All zeros.
    pub const ZERO: Self = Self {
        x: [[0.0; L]; N],
        w: [[0.0; L]; N],
    };

    /// Point `l`.
    #[inline(always)]
    pub fn point(&self, l: usize) -> VarState<N, 1> {
        VarState::new(
            core::array::from_fn(|i| self.x[i][l]),
            [core::array::from_fn(|i| self.w[i][l])],
        )
    }

    /// Point `l` becomes `y` (its quadrature, unused in this form, is dropped).
    #[inline(always)]
    pub fn set_point(&mut self, l: usize, y: &VarState<N, 1>) {
        for i in 0..N {
            self.x[i][l] = y.x[i];
            self.w[i][l] = y.w[0][i];
        }
    }

    /// Point `l`'s tangent vector becomes `w`.
    #[inline(always)]
    pub fn set_tangent(&mut self, l: usize, w: &[f64; N]) {
        for (row, v) in self.w.iter_mut().zip(w) {
            row[l] = *v;
        }
    }

    /// Every row (the `N` of `x`, then the `N` of `w`) as one slice.
    #[inline(always)]
    fn rows(&self) -> &[[f64; L]] {
        // SAFETY: `repr(C)` with two fields [[f64; L]; N]: arrays have no padding and both
        // fields have the alignment of f64, so the struct is exactly 2N consecutive rows.
        unsafe { core::slice::from_raw_parts((self as *const Self).cast::<[f64; L]>(), 2 * N) }
    }

    /// Every row as one mutable slice (see `rows`).
    #[inline(always)]
    fn rows_mut(&mut self) -> &mut [[f64; L]] {
        // SAFETY: as in `rows`; the exclusive borrow of `self` covers the whole slice.
        unsafe { core::slice::from_raw_parts_mut((self as *mut Self).cast::<[f64; L]>(), 2 * N) }
    }
}

/// `row` as an opaque address, so that a loop over rows handles one whole row (all its lanes)
/// per vector operation: otherwise the optimiser vectorises such loops across the rows, one
/// lane of eight rows gathered into a vector and the results scattered back (352 gather and
/// scatter instructions in the AVX-512 build of the maps' driver, most of its own time).
/// The callers read the rows they need into values before writing a result row whole: an
/// opaque address may alias any other, so lane-by-lane writes through it would force every
/// later read to be redone, lane by lane.
#[inline(always)]
pub(crate) fn one_row<T>(row: T) -> T {
    core::hint::black_box(row)
}

/// The stage derivatives of `L` points at once (`t[l]`, `y` → `dy`). A trait rather than a
/// closure so that an `#[inline(always)]` implementation is compiled into the caller's
/// instruction-set build (a closure is a function of its own, built for the baseline when the
/// optimiser does not inline it).
pub(crate) trait LaneField<const N: usize, const L: usize> {
    fn eval(&mut self, t: &[f64; L], y: &LaneStates<N, L>, dy: &mut LaneStates<N, L>);
}

/// The stage derivatives, running sum and stage points of one RK4 step of [`LaneStates`].
#[derive(Debug, Clone)]
pub(crate) struct LaneRk4Scratch<const N: usize, const L: usize> {
    k: LaneStates<N, L>,
    acc: LaneStates<N, L>,
    tmp: LaneStates<N, L>,
}

impl<const N: usize, const L: usize> LaneRk4Scratch<N, L> {
    pub(crate) const ZERO: Self = Self {
        k: LaneStates::ZERO,
        acc: LaneStates::ZERO,
        tmp: LaneStates::ZERO,
    };
}

/// One RK4 step of the points `y`, point `l` from time `t[l]` with step `h[l]`; returns, per
/// point, whether its new state and tangent are finite. The operations of
/// [`Rk4`](super::Rk4)'s step per point, in the same order.
#[inline(always)]
pub(crate) fn rk4_step_lanes<const N: usize, const L: usize>(
    t: &[f64; L],
    h: &[f64; L],
    y: &mut LaneStates<N, L>,
    scratch: &mut LaneRk4Scratch<N, L>,
    field: &mut impl LaneField<N, L>,
) -> [bool; L] {
    let LaneRk4Scratch { k, acc, tmp } = scratch;
    let mut half = [0.0; L];
    let mut t_half = [0.0; L];
    let mut t_end = [0.0; L];
    let mut sixth = [0.0; L];
    for l in 0..L {
        half[l] = 0.5 * h[l];
        t_half[l] = t[l] + half[l];
        t_end[l] = t[l] + h[l];
        sixth[l] = h[l] / 6.0;
    }
    // One loop over the stages, the field (the lanes kernel, inlined) written once, as in
    // `Rk4::rk4_step`.
    let times = [t, &t_half, &t_half, &t_end];
    let to_next = [&half, &half, h];
    for s in 0..4 {
        let at = if s == 0 { &*y } else { &*tmp };
        field.eval(times[s], at, k);
        if s == 3 {
            break;
        }
        stage(acc, tmp, y, k, to_next[s], s == 0);
    }
    // `y += h/6 (acc + k)` with a `v · 0` sum per point: finite → 0, else NaN.
    let mut check = [0.0; L];
    for ((s, a), k) in y.rows_mut().iter_mut().zip(acc.rows()).zip(k.rows()) {
        let s = one_row(s);
        let (mut row, a, k) = (*s, *a, *k);
        for l in 0..L {
            row[l] += sixth[l] * (a[l] + k[l]);
            check[l] += row[l] * 0.0;
        }
        *s = row;
    }
    let mut finite = [false; L];
    for l in 0..L {
        finite[l] = check[l].is_finite();
    }
    finite
}

/// One stage's combinations, row by row: `tmp = y + c k` and `acc += 2 k` (`first`: `acc = k`).
#[inline(always)]
fn stage<const N: usize, const L: usize>(
    acc: &mut LaneStates<N, L>,
    tmp: &mut LaneStates<N, L>,
    y: &LaneStates<N, L>,
    k: &LaneStates<N, L>,
    c: &[f64; L],
    first: bool,
) {
    let rows = acc.rows_mut().iter_mut().zip(tmp.rows_mut());
    for ((a, s), (y, k)) in rows.zip(y.rows().iter().zip(k.rows())) {
        let (a, s) = (one_row(a), one_row(s));
        let (mut sum, mut point, y, k) = (*a, [0.0; L], *y, *k);
        for l in 0..L {
            if first {
                sum[l] = k[l];
            } else {
                sum[l] += 2.0 * k[l];
            }
            point[l] = y[l] + c[l] * k[l];
        }
        (*a, *s) = (sum, point);
    }
}
