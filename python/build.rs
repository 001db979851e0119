//! No build step: this file exists so that the `[build-dependencies]` of Cargo.toml take part in
//! feature unification (see there).
fn main() {}
