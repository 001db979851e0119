//! Parts of the Lyapunov machinery on their own: the sign verdicts, the statistics, the
//! re-orthonormalisation and the batches of the batch-means error.

use twv_analysis::lyapunov::*;

mod classify {
    use super::*;

    const RULE: SignRule = SignRule {
        z: 3.0,
        floor: 0.005,
        resolution: 0.01,
    };

    fn c(l: &[f64], s: &[f64]) -> Classification {
        classify(l, s, &RULE, false).0
    }

    #[test]
    fn verdicts() {
        assert_eq!(
            c(&[0.9, 0.001, -14.5], &[0.02, 0.001, 0.02]),
            Classification::Positive { positive: 1 }
        );
        assert_eq!(
            c(&[-0.5, -2.0], &[0.01, 0.01]),
            Classification::StableFixedPoint
        );
        assert_eq!(
            c(&[0.001, -2.0], &[0.001, 0.01]),
            Classification::Neutral { zero: 1, of: 2 }
        );
        assert!(matches!(
            c(&[0.3, -1.0], &[0.2, 0.01]),
            Classification::NotConverged { index: 0, .. }
        ));
        let json = serde_json::to_value(Classification::StableFixedPoint).unwrap();
        assert_eq!(json["kind"], "stable_fixed_point");
        assert!(json["text"].as_str().unwrap().starts_with("all exponents"));
    }

    /// A large negative exponent does not hide small positive ones (hyper-Rössler-like
    /// spectrum): the decision uses each exponent's own error, and flips when the error does.
    #[test]
    fn a_contracting_direction_does_not_hide_positive_exponents() {
        let rule = SignRule {
            z: 3.0,
            floor: 3e-4,
            resolution: 0.05 * 24.7,
        };
        let l = [0.110, 0.021, 0.0001, -24.7];
        let (verdict, signs) = classify(&l, &[0.003, 0.001, 0.0002, 0.01], &rule, false);
        assert_eq!(verdict, Classification::Positive { positive: 2 });
        assert_eq!(signs[1].sign, ExponentSign::Positive);
        assert_eq!(signs[2].sign, ExponentSign::Zero);
        assert_eq!(verdict.kind(), "hyperchaotic");
        // The same λ2 with a ten times larger error is no longer significant.
        let (verdict, signs) = classify(&l, &[0.003, 0.01, 0.0002, 0.01], &rule, false);
        assert_eq!(signs[1].sign, ExponentSign::Zero);
        assert_eq!(verdict, Classification::Positive { positive: 1 });
    }

    #[test]
    fn the_floor_absorbs_polynomial_growth() {
        // λ above 3σ but below the floor: zero, decided by the floor.
        let d = RULE.decide(0.004, 0.0001);
        assert_eq!(
            (d.sign, d.test),
            (ExponentSign::Zero, SignTest::WithinResolution)
        );
        let d = RULE.decide(0.006, 0.0001);
        assert_eq!(
            (d.sign, d.test),
            (ExponentSign::Positive, SignTest::Significant)
        );
        // Unknown error: never significant, never zero.
        let d = RULE.decide(1.0, f64::NAN);
        assert_eq!((d.sign, d.error), (ExponentSign::Undecided, None));
    }
}

mod stats {
    use super::*;

    #[test]
    fn kaplan_yorke_lorenz() {
        let d = kaplan_yorke(&[0.9056, 0.0, -14.5723], true).unwrap();
        assert!((d - (2.0 + 0.9056 / 14.5723)).abs() < 1e-12);
        assert_eq!(kaplan_yorke(&[-1.0, -2.0], true), Some(0.0));
        assert_eq!(kaplan_yorke(&[1.0, 0.5], false), None);
        assert_eq!(kaplan_yorke(&[1.0, -1.0], true), Some(2.0));
    }

    #[test]
    fn batch_means_of_constant_is_zero() {
        assert_eq!(batch_means_stderr(&[2.0; 20], 4), 0.0);
        let s = batch_means_stderr(&[0.0, 1.0, 0.0, 1.0, 0.0, 3.0], 3);
        // Batch means 0.5, 0.5, 1.5: sd = 0.57735, / √3.
        assert!((s - (1.0f64 / 3.0).sqrt() / 3f64.sqrt()).abs() < 1e-12);
    }
}

mod qr {
    use super::*;

    #[test]
    fn q_orthonormal_and_r_positive() {
        let w0 = [
            [1.0, 2.0, 3.0, 4.0],
            [-2.0, 0.5, 1.0, 0.0],
            [0.3, -1.0, 2.0, 5.0],
        ];
        let mut w = w0;
        let r = orthonormalize(&mut w);
        for i in 0..3 {
            assert!(r[i] > 0.0);
            for j in 0..3 {
                let d: f64 = (0..4).map(|k| w[i][k] * w[j][k]).sum();
                assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
        // R_00 = ‖w0[0]‖ and the first column keeps its direction.
        let n0 = (30.0f64).sqrt();
        assert!((r[0] - n0).abs() < 1e-13);
        assert!((w[0][3] - 4.0 / n0).abs() < 1e-14);
        // |det| of the Gram matrix is preserved: Π R_kk² = det(W Wᵀ).
        let g = |i: usize, j: usize| (0..4).map(|k| w0[i][k] * w0[j][k]).sum::<f64>();
        let det = g(0, 0) * (g(1, 1) * g(2, 2) - g(1, 2) * g(2, 1))
            - g(0, 1) * (g(1, 0) * g(2, 2) - g(1, 2) * g(2, 0))
            + g(0, 2) * (g(1, 0) * g(2, 1) - g(1, 1) * g(2, 0));
        let prod: f64 = r.iter().map(|x| x * x).product();
        assert!((prod / det - 1.0).abs() < 1e-12);
    }
}

mod batches {
    use super::*;

    #[test]
    fn batches_drop_the_leftover_at_the_start() {
        let b = Batches::new(23, 5);
        assert_eq!((b.count, b.size, b.first), (5, 4, 3));
        assert_eq!(b.of(3), None);
        assert_eq!(b.of(4), Some(0));
        assert_eq!(b.of(7), Some(0));
        assert_eq!(b.of(8), Some(1));
        assert_eq!(b.of(23), Some(4));
    }
}
