//! The variational state and the fused vector operations the steppers are built from.

/// A point of the variational system: the state `x`, `K` tangent vectors `w[k]`, and the
/// quadrature ∫ tr(∂F/∂x) dt.
///
/// The steppers use the same type for stage derivatives (then `trace_integral` holds tr J).
/// `repr(C)` keeps the layout one contiguous block, which the fused loops below stream through.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct VarState<const N: usize, const K: usize> {
    /// The state x.
    pub x: [f64; N],
    /// The tangent vectors, one row each.
    pub w: [[f64; N]; K],
    /// ∫ tr(∂F/∂x) dt since the stepper started (0 unless the trace quadrature is on).
    pub trace_integral: f64,
}

impl<const N: usize, const K: usize> VarState<N, K> {
    /// All zeros.
    pub const ZERO: Self = Self {
        x: [0.0; N],
        w: [[0.0; N]; K],
        trace_integral: 0.0,
    };

    /// A state with the given x and tangents and a zero quadrature.
    pub fn new(x: [f64; N], w: [[f64; N]; K]) -> Self {
        Self {
            x,
            w,
            trace_integral: 0.0,
        }
    }

    /// Number of f64 components: x, the tangents, and the quadrature.
    pub const LEN: usize = N + N * K + 1;

    /// All components as one slice, in the order `x`, `w[0]`, …, `w[K−1]`, `trace_integral`.
    #[inline(always)]
    pub fn as_slice(&self) -> &[f64] {
        // SAFETY: `repr(C)` with fields [f64; N], [[f64; N]; K], f64: every field has the
        // alignment and stride of f64 and arrays have no padding, so the struct is exactly
        // LEN consecutive, initialised f64 values.
        unsafe { core::slice::from_raw_parts((self as *const Self).cast::<f64>(), Self::LEN) }
    }

    /// All components as one mutable slice (see [`as_slice`](Self::as_slice)).
    #[inline(always)]
    pub fn as_mut_slice(&mut self) -> &mut [f64] {
        // SAFETY: as in `as_slice`; the exclusive borrow of `self` covers the whole slice.
        unsafe { core::slice::from_raw_parts_mut((self as *mut Self).cast::<f64>(), Self::LEN) }
    }

    /// Applies `op` to every component of the two outputs `self`, `b` and the inputs `c`, `d`:
    /// two results from one pass over memory.
    ///
    /// One flat loop over the contiguous block (rather than nested loops over x and the rows of
    /// w) is what lets the compiler vectorise the stage arithmetic.
    #[inline(always)]
    pub(crate) fn zip_pair(
        &mut self,
        b: &mut Self,
        c: &Self,
        d: &Self,
        mut op: impl FnMut(&mut f64, &mut f64, f64, f64),
    ) {
        for (((a, b), c), d) in self
            .as_mut_slice()
            .iter_mut()
            .zip(b.as_mut_slice().iter_mut())
            .zip(c.as_slice())
            .zip(d.as_slice())
        {
            op(a, b, *c, *d);
        }
    }

    /// `self += c (a + k)` and whether every result is finite, in one pass: the last RK4
    /// update with its blow-up check. The check is a boolean AND, which the compiler may
    /// reorder, so the loop vectorises whole: an earlier form summed `v · 0` in four lanes of
    /// floating-point additions, which LLVM kept scalar (vehicle8's preset: 31 instructions per
    /// 4 values, half the RK4 step's instructions outside the kernel, per callgrind).
    #[inline(always)]
    pub(crate) fn add_sum_checked(&mut self, c: f64, a: &Self, k: &Self) -> bool {
        let mut finite = true;
        for ((s, a), k) in self
            .as_mut_slice()
            .iter_mut()
            .zip(a.as_slice())
            .zip(k.as_slice())
        {
            *s += c * (a + k);
            finite &= s.is_finite();
        }
        finite
    }

    /// Which part is non-finite, if any (NaN or ±∞ anywhere).
    ///
    /// A boolean AND of `is_finite` per part, as in [`Self::add_sum_checked`]: the compiler may
    /// reorder it, so it vectorises (a floating-point sum of `v · 0` it may not, and kept scalar).
    /// Dormand–Prince asks this of every step.
    #[inline]
    pub(crate) fn non_finite_part(&self) -> Option<super::BlowUpPart> {
        use super::BlowUpPart;
        let all_finite = |values: &[f64]| values.iter().fold(true, |ok, v| ok & v.is_finite());
        if !all_finite(&self.x) {
            return Some(BlowUpPart::State);
        }
        if !all_finite(self.w.as_flattened()) {
            return Some(BlowUpPart::Tangent);
        }
        if !self.trace_integral.is_finite() {
            return Some(BlowUpPart::Trace);
        }
        None
    }
}

/// One stage derivative: `dy = (F, J w, tr J)` at `(t, y)`.
#[inline(always)]
pub(crate) fn eval_stage<F, const N: usize, const K: usize>(
    field: &F,
    t: f64,
    y: &VarState<N, K>,
    trace: bool,
    dy: &mut VarState<N, K>,
) where
    F: super::VectorField<N>,
{
    dy.trace_integral = if trace {
        field.eval_trace::<K>(t, &y.x, &y.w, &mut dy.x, &mut dy.w)
    } else {
        field.eval::<K>(t, &y.x, &y.w, &mut dy.x, &mut dy.w);
        0.0
    };
}
