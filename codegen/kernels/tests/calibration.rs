//! `isa::Calibration`: each build the CPU may run is timed in turn, then the fastest is kept —
//! whichever it is, so the choice follows the times, not the order of the instruction sets.

use twv_kernels::isa::{best, force, Calibration, Isa};

/// Feeds `calibration` the time `cost(isa)` for every timed call; returns the builds it tried.
fn calibrate(calibration: &mut Calibration, mut cost: impl FnMut(Isa) -> f64) -> Vec<Isa> {
    let mut tried = Vec::new();
    loop {
        let (isa, timed) = calibration.next();
        if !timed {
            return tried;
        }
        tried.push(isa);
        calibration.record(isa, cost(isa));
    }
}

#[test]
fn the_fastest_build_is_kept_whichever_it_is() {
    // Only the builds the CPU has: the lower `force` limits are enough to show each case.
    let limits: Vec<Isa> = [Isa::Avx512, Isa::Avx2]
        .into_iter()
        .filter(|isa| best() >= *isa)
        .collect();
    for limit in limits {
        force(limit);
        let allowed: Vec<Isa> = [Isa::Avx512, Isa::Avx2, Isa::Baseline]
            .into_iter()
            .filter(|isa| *isa <= limit)
            .collect();
        for fastest in &allowed {
            // The fastest build costs 1; the others 2 and 3, one call of each slowed tenfold
            // (a scheduler hiccup must not decide).
            let mut calibration = Calibration::NEW;
            let mut hiccup = allowed.clone();
            let tried = calibrate(&mut calibration, |isa| {
                let base = if isa == *fastest {
                    1.0
                } else {
                    2.0 + f64::from(u8::from(isa == Isa::Baseline))
                };
                if let Some(i) = hiccup.iter().position(|h| *h == isa) {
                    hiccup.remove(i);
                    return base * 10.0;
                }
                base
            });
            for isa in &allowed {
                let n = tried.iter().filter(|t| *t == isa).count();
                assert_eq!(
                    n,
                    Calibration::ROUNDS as usize,
                    "{limit:?}: {isa:?} tried {n} times"
                );
            }
            assert_eq!(
                calibration.next(),
                (*fastest, false),
                "{limit:?}: {tried:?}"
            );
        }
    }
    // One build only: nothing to time.
    force(Isa::Baseline);
    assert_eq!(Calibration::NEW.next(), (Isa::Baseline, false));
    // A limit lowered after the choice is obeyed. (NEON builds only the lanes kernel, not the
    // steps: on aarch64 the steps' best build is the baseline.)
    force(best());
    let top = if best() == Isa::Neon {
        Isa::Baseline
    } else {
        best()
    };
    let mut calibration = Calibration::NEW;
    calibrate(&mut calibration, |isa| if isa == top { 1.0 } else { 5.0 });
    assert_eq!(calibration.next().0, top);
    force(Isa::Baseline);
    assert_eq!(calibration.next().0, Isa::Baseline);
    force(Isa::Avx512);
}
