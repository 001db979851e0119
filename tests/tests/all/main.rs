//! The cross-crate tests, one module per subject, in one test binary: the analysis library's
//! generic code is instantiated and linked once instead of once per file (the separate binaries
//! had made the test build the longest step of the test command). `tests/tests/no_alloc.rs`
//! stays its own binary because it installs a counting global allocator.

mod common;

mod api;
mod audit;
mod bicycle_runs;
mod codegen;
mod control;
mod docs;
mod firmware;
mod hand_file;
mod hand_model;
mod isa;
mod jit;
mod jobs;
mod linear;
mod lyapunov;
mod lyapunov_parts;
mod machine;
mod output;
mod properties;
mod report;
mod serve;
mod steady;
mod steer;
mod steer_filter;
mod steer_map;
mod sweep;
mod sweep_lanes;
mod uncertainty;
mod workspace;
