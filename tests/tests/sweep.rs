//! Stability-map sweeps (issue 6): sharded and unsharded runs merge to the same bytes, a
//! complete shard is skipped on resume, the spectral-abscissa boundary sits at Kp = M_x g,
//! merge refuses missing, duplicate and foreign shards, and the shard comes from a Slurm array
//! or a Kubernetes indexed job.

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};

use clap::Parser;
use twv_analysis::cli::model::ModelArgs;
use twv_analysis::cli::{run, Cli};
use twv_analysis::plot::zero_contour;
use twv_analysis::sweep::{collect, Axis, Grid, Shard, SweepError};

/// A fresh folder under the temp dir.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twv-sweep-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn twv(args: &[&str]) -> anyhow::Result<()> {
    let mut argv = vec!["twv"];
    argv.extend_from_slice(args);
    run(Cli::try_parse_from(argv)?)
}

fn sweep(dir: &Path, grid: &[&str], shard: &str) {
    let mut args = vec!["sweep", "--out", dir.to_str().unwrap(), "--shard", shard];
    args.extend_from_slice(grid);
    twv(&args).unwrap();
}

fn merge(dir: &Path) -> anyhow::Result<()> {
    twv(&["merge", dir.to_str().unwrap()])
}

fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    ["map.csv", "map.json", "map.svg"]
        .iter()
        .map(|n| (n.to_string(), fs::read(dir.join(n)).unwrap()))
        .collect()
}

const SPECTRAL: [&str; 6] = [
    "--kp",
    "0:2400:25",
    "--kd",
    "100:1000:4",
    "--metric",
    "spectral-abscissa",
];

/// A small nonlinear map: a falling column (Kp < M_x g) and stable points.
const LYAPUNOV: [&str; 6] = [
    "--kp",
    "800:4000:3",
    "--kd",
    "500:2000:2",
    "--metric",
    "max-lyapunov",
];

#[test]
fn sharded_merge_equals_unsharded_and_resume_skips() {
    for (name, grid) in [("spectral", &SPECTRAL), ("lyapunov", &LYAPUNOV)] {
        let whole = scratch(&format!("{name}-whole"));
        sweep(&whole, grid, "0/1");
        merge(&whole).unwrap();
        let parts = scratch(&format!("{name}-parts"));
        for i in 0..3 {
            sweep(&parts, grid, &format!("{i}/3"));
        }
        merge(&parts).unwrap();
        assert_eq!(outputs(&whole), outputs(&parts), "{name}: same bytes");

        // Resume: a complete shard is not recomputed (file untouched).
        let shard = parts.join("shard-1-of-3.json");
        let (before, mtime) = (
            fs::read(&shard).unwrap(),
            fs::metadata(&shard).unwrap().modified().unwrap(),
        );
        sweep(&parts, grid, "1/3");
        assert_eq!(fs::read(&shard).unwrap(), before);
        assert_eq!(fs::metadata(&shard).unwrap().modified().unwrap(), mtime);
        merge(&parts).unwrap();
        assert_eq!(
            outputs(&whole),
            outputs(&parts),
            "{name}: same bytes after resume"
        );
        fs::remove_dir_all(&whole).unwrap();
        fs::remove_dir_all(&parts).unwrap();
    }
}

#[test]
fn lyapunov_map_has_statuses_not_aborts() {
    let dir = scratch("lyapunov-status");
    sweep(&dir, &LYAPUNOV, "0/1");
    let map = collect(&dir).unwrap();
    // Kp = 800 < M_x g: the vehicle falls; the other points keep an exponent.
    for p in &map.points {
        if p.kp < 1206.0 {
            assert!(p.value.is_none(), "{p:?}");
        } else {
            assert!(p.value.is_some_and(f64::is_finite), "{p:?}");
        }
    }
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn spectral_boundary_is_kp_equal_mx_g() {
    let loaded = ModelArgs {
        model: Some("vehicle8".into()),
        ..ModelArgs::default()
    }
    .load()
    .unwrap();
    let p = |n: &str| loaded.param(n).unwrap();
    let kp_crit = (p("m1") + p("m2")) * p("g");
    assert!((kp_crit - 123.0 * 9.81).abs() < 1e-9);

    let dir = scratch("boundary");
    sweep(&dir, &SPECTRAL, "0/1");
    let map = collect(&dir).unwrap();
    let grid = map.config.grid;
    let spacing = grid.kp.spacing();
    let values: Vec<f64> = map.points.iter().map(|p| p.value.unwrap()).collect();
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
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn merge_detects_missing_duplicate_and_foreign_shards() {
    let dir = scratch("checks");
    sweep(&dir, &SPECTRAL, "0/3");
    sweep(&dir, &SPECTRAL, "2/3");
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

    sweep(&dir, &SPECTRAL, "1/3");
    collect(&dir).unwrap();
    sweep(&dir, &SPECTRAL, "0/1");
    let err = collect(&dir).unwrap_err();
    assert!(
        matches!(err, SweepError::Duplicate { count: 100, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("shard-0-of-1.json"), "{err}");

    fs::remove_file(dir.join("shard-0-of-1.json")).unwrap();
    let mut other = SPECTRAL.to_vec();
    other[3] = "100:1000:5";
    sweep(&dir, &other, "0/1");
    let err = collect(&dir).unwrap_err();
    assert!(matches!(err, SweepError::MixedConfigs { .. }), "{err}");
    // A resumed shard of another sweep is refused rather than overwritten.
    fs::remove_file(dir.join("shard-0-of-1.json")).unwrap();
    fs::rename(dir.join("shard-0-of-3.json"), dir.join("keep.json")).unwrap();
    sweep(&dir, &other, "0/3");
    fs::rename(dir.join("keep.json"), dir.join("shard-0-of-3.json")).unwrap();
    let mut args = vec!["sweep", "--out", dir.to_str().unwrap(), "--shard", "0/3"];
    args.extend_from_slice(&other);
    assert!(twv(&args)
        .unwrap_err()
        .to_string()
        .contains("another sweep"));
    fs::remove_dir_all(&dir).unwrap();
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
