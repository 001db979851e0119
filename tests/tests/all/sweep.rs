//! Stability-map sweeps through the library's shard layer: sharded and unsharded runs merge to
//! the same bytes, a complete shard is skipped on resume, an interrupted shard resumes from its
//! checkpoint, a folder holds one sweep, merge refuses missing, duplicate and foreign shards,
//! the spectral-abscissa boundary sits at Kp = M_x g, and the max-Lyapunov map shows the same
//! stability boundary as the linear loop (and its values are the loop's decay rates).

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use twv_analysis::api::{
    analyse, run_shard, sweep, LinearSettings, Progress, ShardOptions, ShardOutcome, Silent,
    SweepSettings,
};
use twv_analysis::linear::{CartPendulum, PidGains};
use twv_analysis::model::{ModelSpec, ResolvedModel};
use twv_analysis::plot::zero_contour;
use twv_analysis::sweep::{collect, merge, Axis, Grid, Metric, Shard, Status, SweepError};

/// A fresh folder under the temp dir (not created: the shard layer creates it).
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twv-sweep-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    dir
}

fn vehicle8() -> ResolvedModel {
    ModelSpec::shipped("vehicle8").resolve().unwrap()
}

fn grid(kp: &str, kd: &str) -> Grid {
    Grid {
        kp: Axis::parse("kp", kp).unwrap(),
        kd: Axis::parse("kd", kd).unwrap(),
        ki: None,
        params: Vec::new(),
    }
}

/// A small linear map.
fn spectral() -> SweepSettings {
    SweepSettings::new(grid("0:2400:25", "100:1000:4"), Metric::SpectralAbscissa)
}

/// A small nonlinear map: a falling column (Kp < M_x g) and stable points.
fn lyapunov() -> SweepSettings {
    SweepSettings::new(grid("800:4000:3", "500:2000:2"), Metric::MaxLyapunov)
}

fn shard(dir: &Path, settings: &SweepSettings, text: &str) -> ShardOutcome {
    let model = vehicle8();
    run_shard(
        &model,
        settings,
        Shard::parse(text).unwrap(),
        dir,
        ShardOptions::default(),
        &Silent,
    )
    .unwrap()
}

fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    ["map.csv", "map.json", "map.svg"]
        .iter()
        .map(|n| (n.to_string(), fs::read(dir.join(n)).unwrap()))
        .collect()
}

#[test]
fn sharded_merge_equals_unsharded_and_resume_skips() {
    for (name, settings) in [("spectral", spectral()), ("lyapunov", lyapunov())] {
        let whole = scratch(&format!("{name}-whole"));
        shard(&whole, &settings, "0/1");
        merge(&whole).unwrap();
        let parts = scratch(&format!("{name}-parts"));
        for i in 0..3 {
            shard(&parts, &settings, &format!("{i}/3"));
        }
        merge(&parts).unwrap();
        assert_eq!(outputs(&whole), outputs(&parts), "{name}: same bytes");

        // Resume: a complete shard is not recomputed (file untouched).
        let file = parts.join("shard-1-of-3.json");
        let (before, mtime) = (
            fs::read(&file).unwrap(),
            fs::metadata(&file).unwrap().modified().unwrap(),
        );
        assert!(matches!(
            shard(&parts, &settings, "1/3"),
            ShardOutcome::Skipped { .. }
        ));
        assert_eq!(fs::read(&file).unwrap(), before);
        assert_eq!(fs::metadata(&file).unwrap().modified().unwrap(), mtime);
        fs::remove_dir_all(&whole).unwrap();
        fs::remove_dir_all(&parts).unwrap();
    }
}

/// Cancels after `after` units of progress (a Ctrl-C in the middle of a shard).
struct CancelAfter {
    after: u64,
    done: AtomicU64,
}

impl Progress for CancelAfter {
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Ordering::SeqCst);
    }
    fn cancelled(&self) -> bool {
        self.done.load(Ordering::SeqCst) >= self.after
    }
}

/// SIGINT in the middle of a shard keeps the finished chunks; the rerun computes only the rest
/// and writes the same bytes as an uninterrupted run.
#[test]
fn an_interrupted_shard_resumes_from_its_checkpoint() {
    let model = vehicle8();
    let settings = SweepSettings::new(grid("800:4000:8", "500:2000:8"), Metric::MaxLyapunov);
    let whole = scratch("interrupt-whole");
    shard(&whole, &settings, "0/1");
    let dir = scratch("interrupt");
    let cancel = CancelAfter {
        after: 24,
        done: AtomicU64::new(0),
    };
    let outcome = run_shard(
        &model,
        &settings,
        Shard::WHOLE,
        &dir,
        ShardOptions::default(),
        &cancel,
    )
    .unwrap();
    let ShardOutcome::Interrupted {
        checkpoint, done, ..
    } = outcome
    else {
        panic!("expected an interruption, got {outcome:?}")
    };
    assert!(done > 0 && done < 64, "{done}");
    assert!(checkpoint.exists());
    assert!(!dir.join("shard-0-of-1.json").exists());
    let ShardOutcome::Written { resumed, .. } = shard(&dir, &settings, "0/1") else {
        panic!("expected the rerun to finish")
    };
    assert_eq!(resumed, done);
    assert!(
        !checkpoint.exists(),
        "the checkpoint is removed once the shard is complete"
    );
    assert_eq!(
        fs::read(dir.join("shard-0-of-1.json")).unwrap(),
        fs::read(whole.join("shard-0-of-1.json")).unwrap()
    );
    fs::remove_dir_all(&whole).unwrap();
    fs::remove_dir_all(&dir).unwrap();
}

/// A folder holds one sweep: a second sweep with another config is refused (not overwritten),
/// and a run that fails leaves no folder behind.
#[test]
fn a_folder_holds_one_sweep() {
    let model = vehicle8();
    let dir = scratch("one-sweep");
    shard(&dir, &spectral(), "0/1");
    let mut other = spectral();
    other.grid.kd.n = 5;
    let err = run_shard(
        &model,
        &other,
        Shard::WHOLE,
        &dir,
        ShardOptions { force: true },
        &Silent,
    )
    .unwrap_err();
    assert!(err.to_string().contains("holds another sweep"), "{err}");
    collect(&dir).unwrap();
    fs::remove_dir_all(&dir).unwrap();

    let fresh = scratch("refused-grid");
    let huge = SweepSettings::new(
        grid("0:8000:1000000", "0:4000:1000000"),
        Metric::MaxLyapunov,
    );
    let err = run_shard(
        &model,
        &huge,
        Shard::WHOLE,
        &fresh,
        ShardOptions::default(),
        &Silent,
    )
    .unwrap_err();
    assert!(err.to_string().contains("1000000000000 points"), "{err}");
    assert!(!fresh.exists(), "no empty folder left behind");
}

#[test]
fn lyapunov_map_has_statuses_not_aborts() {
    let points = sweep(&vehicle8(), &lyapunov(), &Silent).unwrap();
    // Kp = 800 < M_x g: the vehicle falls; the other points keep an exponent.
    for p in &points {
        if p.kp < 1206.0 {
            assert_eq!(p.status, Status::Fell, "{p:?}");
        } else {
            assert!(p.value.is_some_and(f64::is_finite), "{p:?}");
        }
    }
}

#[test]
fn a_settle_distance_that_is_not_a_distance_is_refused_by_name() {
    for bad in [0.0, -1e-3, f64::NAN, f64::INFINITY] {
        let mut settings = lyapunov();
        settings.metric_settings.settle_distance = Some(bad);
        let e = sweep(&vehicle8(), &settings, &Silent)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("metric_settings.settle_distance")
                && e.contains("null turns the shortcut off"),
            "{bad}: {e}"
        );
    }
    // A request that leaves fields out gets their defaults; null turns the tail off.
    let partial: twv_analysis::sweep::MetricSettings =
        serde_json::from_str(r#"{"settle_distance": null, "iterations": 20}"#).unwrap();
    assert_eq!(partial.settle_distance, None);
    assert_eq!(partial.iterations, 20);
    assert_eq!(partial.h, twv_analysis::sweep::MetricSettings::default().h);
}

#[test]
fn spectral_boundary_is_kp_equal_mx_g() {
    let model = vehicle8();
    let p = |n: &str| model.param(n).unwrap();
    let kp_crit = (p("m1") + p("m2")) * p("g");
    let settings = spectral();
    let grid = settings.grid.clone();
    let points = sweep(&model, &settings, &Silent).unwrap();
    let spacing = grid.kp.spacing();
    let values: Vec<f64> = points.iter().map(|p| p.value.unwrap()).collect();
    // Along every row the first stable Kp and the last unstable one bracket M_x g.
    for row in values.chunks(grid.kp.n) {
        let i = row.iter().position(|v| *v < 0.0).unwrap();
        assert!(row[i..].iter().all(|v| *v < 0.0));
        let (lo, hi) = (grid.kp.value(i - 1), grid.kp.value(i));
        assert!(lo < kp_crit && kp_crit <= hi, "{lo} < {kp_crit} ≤ {hi}");
    }
    // The drawn boundary (zero contour) is within one grid spacing of Kp = M_x g.
    let segments = zero_contour(&grid.kp.values(), &grid.kd.values(), &values);
    assert_eq!(segments.len(), grid.kd.n - 1);
    for s in &segments {
        for (kp, _) in s {
            assert!((kp - kp_crit).abs() < spacing, "contour at Kp = {kp}");
        }
    }
}

/// The study setpoint 0.03·sinΦ scales the effective Kp and Ki by 0.97 at the upright.
const SETPOINT_GAIN: f64 = 0.97;

/// The nonlinear map's stability (λ1 of the pitch loop < 0, or a fall) agrees with the linear
/// pitch loop's at the same effective gains wherever the point is more than one grid cell from
/// the linear boundary; the drawn zero contours therefore agree to within one cell.
#[test]
fn max_lyapunov_boundary_is_the_linear_boundary() {
    let model = vehicle8();
    let settings = SweepSettings::new(grid("0:4000:21", "0:2000:21"), Metric::MaxLyapunov);
    let g = settings.grid.clone();
    let nonlinear = sweep(&model, &settings, &Silent).unwrap();
    let scaled = Grid {
        kp: Axis {
            lo: g.kp.lo * SETPOINT_GAIN,
            hi: g.kp.hi * SETPOINT_GAIN,
            n: g.kp.n,
        },
        ..g
    };
    let linear = sweep(
        &model,
        &SweepSettings::new(scaled, Metric::SpectralAbscissa),
        &Silent,
    )
    .unwrap();
    let stable_nl = |i: usize| {
        let p = &nonlinear[i];
        p.status == Status::Ok && p.value.is_some_and(|v| v < 0.0)
    };
    let stable_lin = |i: usize| linear[i].value.is_some_and(|v| v < -1e-9);
    let (nx, ny) = (g.kp.n, g.kd.n);
    let mut compared = 0;
    for j in 0..ny {
        for i in 0..nx {
            let idx = j * nx + i;
            // Skip points with a neighbour (one cell away) on the other side of the linear
            // boundary: the boundary may fall anywhere in that cell.
            let near = (j.saturating_sub(1)..=(j + 1).min(ny - 1)).any(|jj| {
                (i.saturating_sub(1)..=(i + 1).min(nx - 1))
                    .any(|ii| stable_lin(jj * nx + ii) != stable_lin(idx))
            });
            if near {
                continue;
            }
            compared += 1;
            assert_eq!(
                stable_nl(idx),
                stable_lin(idx),
                "Kp {}, Kd {}: nonlinear {:?}, linear {:?}",
                g.kp.value(i),
                g.kd.value(j),
                nonlinear[idx],
                linear[idx]
            );
        }
    }
    assert!(compared > nx * ny / 2, "{compared}");
}

/// Inside the stable region λ1 of the pitch loop is the loop's slowest decay rate, the largest
/// real part σ of its closed-loop poles at the upright (effective gains), for a small tilt: to
/// within the finite-time bound 2 ln κ / T, κ the condition number of the loop's (real) modal
/// basis and T the averaging time (after the transient the tangent lies in the slow mode, whose
/// norm then oscillates by at most κ); where the poles are real and well apart, to 1e-4.
#[test]
fn stable_map_values_are_the_loop_decay_rates() {
    let model = vehicle8();
    let mut settings = SweepSettings::new(grid("2000:8000:4", "500:3500:4"), Metric::MaxLyapunov);
    settings.tilt = 1e-3;
    let horizon = settings.metric_settings.t_sample * settings.metric_settings.iterations as f64;
    let points = sweep(&model, &settings, &Silent).unwrap();
    let p = |n: &str| model.param(n).unwrap();
    let cart = CartPendulum::from_vehicle(p("m1"), p("m2"), p("b"), p("I2_yy"), p("g")).unwrap();
    let (a, b) = cart.matrices();
    let (phi, w_y) = (0, 2);
    for pt in &points {
        let gains = PidGains::pd(pt.kp * SETPOINT_GAIN, pt.kd);
        let lin = analyse(
            &model,
            &LinearSettings {
                gains,
                ..LinearSettings::default()
            },
        )
        .unwrap();
        let sigma = lin.pitch.unwrap().spectral_abscissa.unwrap();
        // The (Φ, Φ̇) block of the closed loop: Φ̈ row gets b·(Kp Φ + Kd Φ̇).
        let m = nalgebra::Matrix2::new(
            a[(phi, phi)] + b[(phi, 0)] * gains.kp,
            a[(phi, w_y)] + b[(phi, 0)] * gains.kd,
            a[(w_y, phi)] + b[(w_y, 0)] * gains.kp,
            a[(w_y, w_y)] + b[(w_y, 0)] * gains.kd,
        );
        let eig = m.complex_eigenvalues();
        let (e0, e1) = (eig[0], eig[1]);
        let basis = if e0.im.abs() > 1e-12 {
            // Real basis (Re v, Im v) of the complex pair: v ∝ (m12, e − m11).
            nalgebra::Matrix2::new(m[(0, 1)], 0.0, e0.re - m[(0, 0)], e0.im)
        } else {
            let col = |e: f64| (m[(0, 1)], e - m[(0, 0)]);
            let (c0, c1) = (col(e0.re), col(e1.re));
            nalgebra::Matrix2::new(c0.0, c1.0, c0.1, c1.1)
        };
        let sv = basis.singular_values();
        let kappa = sv.max() / sv.min();
        let bound = 2.0 * kappa.ln() / horizon + 1e-6;
        let v = pt.value.unwrap();
        println!(
            "Kp {} Kd {}: λ1 = {v:.6}, σ = {sigma:.6} (poles {e0}, {e1}), bound {bound:.4}",
            pt.kp, pt.kd
        );
        assert!(sigma < 0.0 && v < 0.0);
        assert!(
            (v - sigma).abs() <= bound,
            "{pt:?}: {v} vs {sigma} ± {bound}"
        );
        let separated = e0.im.abs() < 1e-12 && (e0.re.abs().max(e1.re.abs())) > 2.0 * sigma.abs();
        if separated {
            assert!(
                (v - sigma).abs() <= 1e-4 * sigma.abs(),
                "{pt:?}: {v} vs {sigma}"
            );
        }
    }
}

#[test]
fn merge_detects_missing_duplicate_and_foreign_shards() {
    let dir = scratch("checks");
    let settings = spectral();
    shard(&dir, &settings, "0/3");
    shard(&dir, &settings, "2/3");
    let err = collect(&dir).unwrap_err();
    assert!(
        matches!(err, SweepError::Missing { count: 33, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("33-65"), "{err}");
    assert!(merge(&dir).is_err());
    assert!(
        !dir.join("map.csv").exists(),
        "no output from a failed merge"
    );

    shard(&dir, &settings, "1/3");
    collect(&dir).unwrap();
    shard(&dir, &settings, "0/1");
    let err = collect(&dir).unwrap_err();
    assert!(
        matches!(err, SweepError::Duplicate { count: 100, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("shard-0-of-1.json"), "{err}");
    fs::remove_file(dir.join("shard-0-of-1.json")).unwrap();

    // A shard of another sweep copied in by hand is refused by the merge.
    let other_dir = scratch("checks-other");
    let mut other = spectral();
    other.grid.kd.n = 5;
    shard(&other_dir, &other, "0/1");
    fs::copy(
        other_dir.join("shard-0-of-1.json"),
        dir.join("shard-0-of-1.json"),
    )
    .unwrap();
    let err = collect(&dir).unwrap_err();
    assert!(matches!(err, SweepError::MixedConfigs { .. }), "{err}");
    fs::remove_dir_all(&dir).unwrap();
    fs::remove_dir_all(&other_dir).unwrap();
}

fn env(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
    let map: HashMap<String, String> = pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    move |k| map.get(k).cloned()
}

#[test]
fn shard_from_slurm_and_kubernetes() {
    let shard = |pairs: &[(&str, &str)], n| Shard::from_env(env(pairs), n);
    assert_eq!(shard(&[], None).unwrap(), Shard::WHOLE);
    let slurm = [
        ("SLURM_ARRAY_TASK_ID", "7"),
        ("SLURM_ARRAY_TASK_MIN", "0"),
        ("SLURM_ARRAY_TASK_COUNT", "16"),
    ];
    assert_eq!(shard(&slurm, None).unwrap(), Shard::new(7, 16).unwrap());
    // --array=1-16: IDs start at MIN.
    let offset = [
        ("SLURM_ARRAY_TASK_ID", "16"),
        ("SLURM_ARRAY_TASK_MIN", "1"),
        ("SLURM_ARRAY_TASK_COUNT", "16"),
    ];
    assert_eq!(shard(&offset, None).unwrap(), Shard::new(15, 16).unwrap());
    let stepped = [
        ("SLURM_ARRAY_TASK_ID", "2"),
        ("SLURM_ARRAY_TASK_COUNT", "8"),
        ("SLURM_ARRAY_TASK_STEP", "2"),
    ];
    assert!(shard(&stepped, None).is_err());
    let k8s = [("JOB_COMPLETION_INDEX", "3")];
    assert!(shard(&k8s, None).is_err(), "count unknown");
    assert_eq!(shard(&k8s, Some(4)).unwrap(), Shard::new(3, 4).unwrap());
    let k8s_env = [("JOB_COMPLETION_INDEX", "3"), ("TWV_SHARDS", "8")];
    assert_eq!(shard(&k8s_env, None).unwrap(), Shard::new(3, 8).unwrap());
    assert!(shard(&[("JOB_COMPLETION_INDEX", "4")], Some(4)).is_err());
    assert!(shard(&[], Some(4)).is_err(), "a count without an index");
    assert_eq!(Shard::parse("2/5").unwrap(), Shard::new(2, 5).unwrap());
    for bad in ["5/5", "1", "a/2", "0/0"] {
        assert!(Shard::parse(bad).is_err(), "{bad}");
    }
}

#[test]
fn shards_tile_the_grid_in_row_major_order() {
    let grid = Grid {
        kp: Axis::parse("kp", "0:10:11").unwrap(),
        kd: Axis::parse("kd", "1:2:2").unwrap(),
        ki: Some(Axis::parse("ki", "0:1:3").unwrap()),
        params: Vec::new(),
    };
    assert_eq!(grid.len(), 66);
    let g = grid.gains(11 * 2 + 11 + 4);
    assert_eq!((g.kp, g.kd, g.ki), (4.0, 2.0, 0.5));
    for n in [1, 3, 7, 66, 100] {
        let mut next = 0;
        for i in 0..n {
            let r = Shard::new(i, n).unwrap().range(grid.len());
            assert_eq!(r.start, next);
            next = r.end;
        }
        assert_eq!(next, grid.len());
    }
    for bad in ["0:1", "1:0:3", "0:1:0", "0:x:3"] {
        assert!(Axis::parse("kp", bad).is_err(), "{bad}");
    }
}

fn param_axis(text: &str) -> twv_analysis::sweep::ParamAxis {
    twv_analysis::sweep::ParamAxis::parse(text).unwrap()
}

/// A map over Kp and the pendulum mass m2: on every m2 row the spectral boundary sits at
/// Kp = (m1 + m2)·g, so it moves with the parameter as the linear loop says.
#[test]
fn parameter_axes_move_the_boundary_with_the_parameter() {
    let model = vehicle8();
    let p = |n: &str| model.param(n).unwrap();
    let mut grid = grid("0:2400:25", "1980:1980:1");
    grid.params = vec![param_axis("m2=4:40:4")];
    let settings = SweepSettings::new(grid.clone(), Metric::SpectralAbscissa);
    let points = sweep(&model, &settings, &Silent).unwrap();
    assert_eq!(points.len(), 25 * 4);
    let mut crits = Vec::new();
    for (k, row) in points.chunks(grid.kp.n).enumerate() {
        let m2 = grid.param_values(k)[0].1;
        let kp_crit = (p("m1") + m2) * p("g");
        crits.push(kp_crit);
        let i = row.iter().position(|q| q.value.unwrap() < 0.0).unwrap();
        let (lo, hi) = (grid.kp.value(i - 1), grid.kp.value(i));
        assert!(
            lo < kp_crit && kp_crit <= hi,
            "m2 = {m2}: {lo} < {kp_crit} ≤ {hi}"
        );
    }
    // The rows differ: m2 from 4 to 40 kg moves the boundary by 36·g ≈ 353 N/rad.
    assert!(crits[3] - crits[0] > 300.0);
}

/// A point of a parameter sweep is the point of the gain sweep on the model with those
/// parameters, bit for bit (the lanes path included), and the map's CSV names the parameters.
#[test]
fn a_parameter_point_equals_the_gain_sweep_of_that_vehicle() {
    let model = vehicle8();
    let mut grid = grid("2000:4000:9", "1500:1500:1");
    grid.params = vec![param_axis("m2=4:12:3"), param_axis("b=0.4:0.7:2")];
    let settings = SweepSettings::new(grid.clone(), Metric::MaxLyapunov);
    let points = sweep(&model, &settings, &Silent).unwrap();
    assert_eq!(points.len(), 9 * 3 * 2);
    for setting in [0, 5] {
        let values = grid.param_values(setting);
        let at = model.with_param_values(&values, "test").unwrap();
        let mut gains_only = grid.clone();
        gains_only.params.clear();
        let direct = sweep(
            &at,
            &SweepSettings::new(gains_only, Metric::MaxLyapunov),
            &Silent,
        )
        .unwrap();
        let block = &points[setting * 9..(setting + 1) * 9];
        for (a, b) in block.iter().zip(&direct) {
            assert_eq!(
                a.value.map(f64::to_bits),
                b.value.map(f64::to_bits),
                "{values:?}"
            );
            assert_eq!(a.status, b.status);
        }
    }
    // Sharded and unsharded merge to the same bytes; the CSV has the parameter columns.
    let mut grid = grid.clone();
    grid.kd = Axis::parse("kd", "1000:2000:2").unwrap();
    let settings = SweepSettings::new(grid, Metric::SpectralAbscissa);
    let (whole, parts) = (scratch("param-whole"), scratch("param-parts"));
    shard(&whole, &settings, "0/1");
    merge(&whole).unwrap();
    for i in 0..3 {
        shard(&parts, &settings, &format!("{i}/3"));
    }
    merge(&parts).unwrap();
    assert_eq!(outputs(&whole), outputs(&parts));
    let csv = fs::read_to_string(whole.join("map.csv")).unwrap();
    assert!(
        csv.starts_with("index,kp,ki,kd,m2,b,value,status\n"),
        "{csv}"
    );
    // Heat maps over (Kp, Kd), one per (m2, b) setting.
    assert!(whole.join("map-5.svg").is_file() && !whole.join("map-6.svg").exists());
    fs::remove_dir_all(&whole).unwrap();
    fs::remove_dir_all(&parts).unwrap();
}

#[test]
fn bad_parameter_axes_are_named() {
    let model = vehicle8();
    let err = |axes: &[&str]| {
        let mut g = grid("0:100:2", "0:100:2");
        g.params = axes.iter().map(|t| param_axis(t)).collect();
        sweep(
            &model,
            &SweepSettings::new(g, Metric::SpectralAbscissa),
            &Silent,
        )
        .unwrap_err()
        .to_string()
    };
    let e = err(&["mass=1:2:2"]);
    assert!(
        e.contains("`mass` is not a parameter of vehicle8") && e.contains("m2"),
        "{e}"
    );
    assert!(err(&["m2=1:2:2", "m2=3:4:2"]).contains("two axes"));
    let e = err(&["m2=-1:5:3"]);
    assert!(e.contains("m2"), "{e}");
    for text in ["m2", "=1:2:3", "m2=1:2", "m2=2:1:3"] {
        assert!(
            twv_analysis::sweep::ParamAxis::parse(text).is_err(),
            "{text}"
        );
    }
}

/// The tasks of an array job start together: four shards set up one new folder at the same
/// moment, take turns at its manifest, and all succeed (regression: the Slurm test found the
/// second task refused with "another twv process is setting up this folder").
#[test]
fn shards_starting_together_share_a_new_folder() {
    let settings = spectral();
    let dir = scratch("together");
    std::thread::scope(|s| {
        for i in 0..4 {
            let (dir, settings) = (&dir, &settings);
            s.spawn(move || shard(dir, settings, &format!("{i}/4")));
        }
    });
    merge(&dir).unwrap();
    let whole = scratch("together-whole");
    shard(&whole, &settings, "0/1");
    merge(&whole).unwrap();
    assert_eq!(outputs(&dir), outputs(&whole));
    fs::remove_dir_all(&dir).unwrap();
    fs::remove_dir_all(&whole).unwrap();
}

/// An operating-point axis: `tilt` sweeps the initial pitch of the nonlinear metrics. Each
/// point has the bits of the gain sweep started from that tilt, and the map shows the region of
/// attraction: a weak loop catches a small tilt and drops a large one.
#[test]
fn a_tilt_axis_maps_the_region_of_attraction() {
    let model = vehicle8();
    let mut grid = grid("1500:2500:9", "800:800:1");
    grid.params = vec![param_axis("tilt=0.1:1.2:3")];
    let settings = SweepSettings::new(grid.clone(), Metric::MaxLyapunov);
    let points = sweep(&model, &settings, &Silent).unwrap();
    for setting in 0..3 {
        let tilt = grid.tilt(setting).unwrap();
        let mut gains_only = grid.clone();
        gains_only.params.clear();
        let direct = SweepSettings {
            tilt,
            ..SweepSettings::new(gains_only, Metric::MaxLyapunov)
        };
        let direct = sweep(&model, &direct, &Silent).unwrap();
        for (a, b) in points[setting * 9..(setting + 1) * 9].iter().zip(&direct) {
            assert_eq!(
                a.value.map(f64::to_bits),
                b.value.map(f64::to_bits),
                "tilt {tilt}"
            );
            assert_eq!(a.status, b.status, "tilt {tilt}");
        }
    }
    // Kp = 1500 catches 0.1 rad and drops 1.2 rad.
    assert_eq!(points[0].status, Status::Ok);
    assert!(points[0].value.unwrap() < 0.0);
    assert_eq!(points[18].status, Status::Fell);
    // The tilt axis belongs to the nonlinear metrics and replaces x0.
    let mut linear = SweepSettings::new(grid.clone(), Metric::SpectralAbscissa);
    let e = sweep(&model, &linear, &Silent).unwrap_err().to_string();
    assert!(
        e.contains("tilt axis applies to the nonlinear metrics"),
        "{e}"
    );
    linear.metric = Metric::MaxLyapunov;
    linear.x0 = Some(vec![0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let e = sweep(&model, &linear, &Silent).unwrap_err().to_string();
    assert!(e.contains("x0") && e.contains("tilt axis"), "{e}");
}
