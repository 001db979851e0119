//! Cross-crate tests live in tests/tests/all/ (one binary) and tests/tests/no_alloc.rs.
