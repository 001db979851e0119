//! No code: the dependencies in Cargo.toml give every build of the workspace one feature set.
