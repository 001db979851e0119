//! `twv_kernels::trig::sin_cos` against the C library (glibc's sin and cos are correctly rounded
//! in all but rare cases, so agreeing with them to 1 ulp means an error below ~1.5 ulp).

use twv_kernels::trig::sin_cos;

/// Distance in units in the last place between two finite doubles of the same sign region.
fn ulps(a: f64, b: f64) -> u64 {
    let key = |v: f64| {
        let bits = v.to_bits() as i64;
        if bits < 0 {
            i64::MIN - bits
        } else {
            bits
        }
    };
    key(a).abs_diff(key(b))
}

/// xorshift64*, uniform in [lo, hi).
struct Uniform(u64);
impl Uniform {
    fn next(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// Largest ulp distance from libm over `n` points of [-r, r], and how many were bit-identical.
fn worst_over(r: f64, n: usize, seed: u64) -> (u64, usize) {
    let mut rng = Uniform(seed);
    let (mut worst, mut same) = (0, 0);
    for _ in 0..n {
        let x = rng.next(-r, r);
        let (s, c) = sin_cos(x);
        let (ds, dc) = (ulps(s, x.sin()), ulps(c, x.cos()));
        worst = worst.max(ds).max(dc);
        same += usize::from(ds == 0 && dc == 0);
    }
    (worst, same)
}

#[test]
fn within_one_ulp_of_libm_on_every_range_the_reduction_covers() {
    for (r, seed) in [(0.785, 1), (4.0, 2), (100.0, 3), (1.0e4, 4), (1.6e6, 5)] {
        let n = 200_000;
        let (worst, same) = worst_over(r, n, seed);
        assert!(worst <= 1, "|x| <= {r}: {worst} ulp from libm");
        // Most results are libm's exactly (fdlibm is not correctly rounded, glibc nearly is); a
        // systematic bias would show as a low share.
        eprintln!("|x| <= {r}: worst {worst} ulp, {same} of {n} bit-identical to libm");
        assert!(
            same * 100 >= n * 90,
            "|x| <= {r}: only {same} of {n} identical"
        );
    }
}

#[test]
fn near_multiples_of_half_pi_where_the_reduction_cancels() {
    // The two- and three-round paths: arguments within a few ulp of k·π/2.
    for k in 1..2000_i32 {
        let centre = f64::from(k) * core::f64::consts::FRAC_PI_2;
        let mut x = centre;
        for _ in 0..4 {
            let (s, c) = sin_cos(x);
            assert!(ulps(s, x.sin()) <= 1, "sin({x:e}) = {s:e} vs {:e}", x.sin());
            assert!(ulps(c, x.cos()) <= 1, "cos({x:e}) = {c:e} vs {:e}", x.cos());
            x = f64::from_bits(x.to_bits() + 1);
        }
        let (s, c) = sin_cos(-centre);
        assert!(ulps(s, (-centre).sin()) <= 1 && ulps(c, (-centre).cos()) <= 1);
    }
}

#[test]
fn special_values_and_the_library_fallback() {
    let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
    for x in [
        0.0,
        -0.0,
        f64::MIN_POSITIVE,
        -5e-324,
        1e-10,
        -1e-8,
        1.7e6,
        -1e22,
        1e300,
        f64::MAX,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
    ] {
        let (s, c) = sin_cos(x);
        assert!(same(s, x.sin()), "sin({x:e}) = {s:e} vs {:e}", x.sin());
        assert!(same(c, x.cos()), "cos({x:e}) = {c:e} vs {:e}", x.cos());
    }
}

#[test]
fn symmetries_hold_exactly() {
    let mut rng = Uniform(9);
    for _ in 0..100_000 {
        let x = rng.next(-50.0, 50.0);
        let (s, c) = sin_cos(x);
        let (sn, cn) = sin_cos(-x);
        assert_eq!(
            (s.to_bits(), c.to_bits()),
            ((-sn).to_bits(), cn.to_bits()),
            "x = {x:e}"
        );
        assert!((s * s + c * c - 1.0).abs() <= 4.0 * f64::EPSILON);
    }
}

/// The arguments that reach every path of the scalar function: tiny, |x| ≤ π/4 (no
/// reduction), one-, two- and three-round reductions (next to k·π/2), both signs, the
/// thresholds' neighbours.
fn every_path() -> Vec<f64> {
    let mut xs = vec![0.0, -0.0, 5e-324, -1e-300, 1e-9, -3.7e-9];
    let mut rng = Uniform(0x5eed);
    for r in [1e-7, 0.5, 0.785, 0.8, 2.0, 40.0, 1e3, 1.6e6] {
        xs.extend((0..3000).map(|_| rng.next(-r, r)));
    }
    for k in 1..1500_i32 {
        let centre = f64::from(k) * core::f64::consts::FRAC_PI_2;
        for d in 0..3 {
            xs.push(f64::from_bits(centre.to_bits() + d));
            xs.push(-f64::from_bits(centre.to_bits() - d));
        }
    }
    for threshold in [0x3FE9_21FB_u64 << 32, 0x3E40_0000_u64 << 32] {
        for d in 0..4 {
            xs.push(f64::from_bits(threshold + d));
            xs.push(-f64::from_bits(threshold - d - 1));
        }
    }
    xs
}

/// `wide_sin_cos` (an 8-lane sincos) against the scalar one at every argument of
/// [`every_path`], lanes mixed from all over the list, and a group with a lane for the C
/// library.
fn lanes_have_the_scalar_bits(wide_sin_cos: impl Fn([f64; 8]) -> ([f64; 8], [f64; 8])) {
    use twv_kernels::lanes::LANES;
    let xs = every_path();
    let n = xs.len() / LANES * LANES;
    let stride = n / LANES;
    for g in 0..stride {
        let x: [f64; LANES] = core::array::from_fn(|l| xs[g + l * stride]);
        let (s, c) = wide_sin_cos(x);
        for l in 0..LANES {
            let (s1, c1) = sin_cos(x[l]);
            assert_eq!(s[l].to_bits(), s1.to_bits(), "sin({:e})", x[l]);
            assert_eq!(c[l].to_bits(), c1.to_bits(), "cos({:e})", x[l]);
        }
    }
    // Groups whose lanes all need no reduction (the fast path), with tiny lanes and ±0.
    for g in 0..64 {
        let x: [f64; LANES] = core::array::from_fn(|l| {
            let t = ((g * LANES + l) as f64 * 0.618_033_988_75).fract();
            match (g + l) % 5 {
                0 => (t - 0.5) * 1e-9,
                1 => -0.0,
                2 => 0.0,
                _ => (t - 0.5) * 1.57,
            }
        });
        let (s, c) = wide_sin_cos(x);
        for l in 0..LANES {
            let (s1, c1) = sin_cos(x[l]);
            assert_eq!(s[l].to_bits(), s1.to_bits(), "sin({:e})", x[l]);
            assert_eq!(c[l].to_bits(), c1.to_bits(), "cos({:e})", x[l]);
        }
    }
    // A lane that needs the C library sends the group lane by lane.
    let x = [0.3, 1e7, f64::NAN, -2.0, 0.0, 1e-12, 3.0, f64::INFINITY];
    let (s, c) = wide_sin_cos(x);
    for l in 0..LANES {
        let (s1, c1) = sin_cos(x[l]);
        assert!(s[l].to_bits() == s1.to_bits() || (s[l].is_nan() && s1.is_nan()));
        assert!(c[l].to_bits() == c1.to_bits() || (c[l].is_nan() && c1.is_nan()));
    }
}

#[test]
fn eight_wide_sin_cos_has_the_bits_of_the_scalar_one_on_every_isa_here() {
    #[cfg(target_arch = "x86_64")]
    {
        use twv_kernels::isa::{best, Isa};
        use twv_kernels::lanes::{wide, wide_avx2};
        if best() >= Isa::Avx512 {
            // SAFETY: the CPU has AVX-512F and VL.
            lanes_have_the_scalar_bits(|x| unsafe { wide::sin_cos(x) });
        } else {
            eprintln!("SKIPPED: the AVX-512 sincos did not run: this CPU has no AVX-512F/VL");
        }
        if best() >= Isa::Avx2 {
            // SAFETY: the CPU has AVX2.
            lanes_have_the_scalar_bits(|x| unsafe { wide_avx2::sin_cos(x) });
        } else {
            eprintln!("SKIPPED: the AVX2 sincos did not run: this CPU has no AVX2");
        }
        eprintln!("SKIPPED: the NEON sincos did not run: it is built for aarch64 only");
    }
    #[cfg(target_arch = "aarch64")]
    {
        use twv_kernels::lanes::wide_neon;
        // SAFETY: NEON is part of every aarch64 CPU.
        lanes_have_the_scalar_bits(|x| unsafe { wide_neon::sin_cos(x) });
        eprintln!("SKIPPED: the AVX-512 and AVX2 sincos did not run: they are built for x86-64");
    }
    // The dispatched entry, whatever build it picks here.
    lanes_have_the_scalar_bits(twv_kernels::lanes::sin_cos);
}

/// `sin_cos_pair` has the bits of `sin_cos` for each of its two angles, whichever paths they
/// take: every argument of `every_path` paired with a shifted copy of the list (both in the
/// unreduced range, one or none), and with the special values.
#[test]
fn paired_sin_cos_has_the_bits_of_the_scalar_one() {
    use twv_kernels::trig::sin_cos_pair;
    let same = |(s, c): (f64, f64), x: f64| {
        let (s1, c1) = sin_cos(x);
        (s.to_bits() == s1.to_bits() || (s.is_nan() && s1.is_nan()))
            && (c.to_bits() == c1.to_bits() || (c.is_nan() && c1.is_nan()))
    };
    let mut xs = every_path();
    xs.extend([f64::NAN, f64::INFINITY, -f64::INFINITY, 1e7, -0.0]);
    let mut unreduced = 0;
    for shift in [1, 7, 3001] {
        for (i, &a) in xs.iter().enumerate() {
            let b = xs[(i + shift) % xs.len()];
            let (pa, pb) = sin_cos_pair(a, b);
            assert!(same(pa, a), "sin_cos_pair({a:e}, {b:e}): first");
            assert!(same(pb, b), "sin_cos_pair({a:e}, {b:e}): second");
            if [a, b]
                .iter()
                .all(|x| (2f64.powi(-27)..=0.785).contains(&x.abs()))
            {
                unreduced += 1;
            }
        }
    }
    // The two-lane path ran, not only the fallback.
    assert!(
        unreduced > 10_000,
        "{unreduced} pairs in the unreduced range"
    );
}
