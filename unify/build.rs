//! Empty: cargo counts build dependencies only for a crate with a build script (Cargo.toml says
//! why this crate has them).
fn main() {}
