//! Helpers shared by the cross-crate test modules.

/// `a` and `b` agree bit for bit, entry by entry (NaN payloads and signs of zero included).
#[track_caller]
pub fn assert_bits(a: &[f64], b: &[f64], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert_eq!(x.to_bits(), y.to_bits(), "{what}[{i}]: {x:e} vs {y:e}");
    }
}

/// Every shipped model with its parameters folded in as constants (two crates, one per kind of
/// parameter source, so that editing `vehicles/paper.toml` rebuilds only the vehicles).
pub mod baked {
    pub use twv_baked_other::*;
    pub use twv_baked_paper::*;
}

/// A path in the repository.
pub fn repo(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(path)
}
