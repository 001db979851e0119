//! The machinery the generated kernels call, kept beside the generated code's one seam (the
//! `twv-model` traits) rather than in it:
//!
//! - [`trig`]: one inline sincos per angle (a Cody–Waite reduction and fdlibm's kernels), the
//!   interpreter's and the generated code's, so the two agree bit for bit;
//! - [`isa`]: the run-time choice between the x86-64 baseline and AVX-512 builds of a kernel;
//! - [`lanes`]: 8-lane arithmetic for kernels that evaluate eight points at once;
//! - [`tangents`]: J·W in the row form every path shares, many tangent vectors at once;
//! - [`zero`]: the structural zeros of dense outputs, opaque so that they are not merged into
//!   512-bit stores.
#![no_std]

pub mod isa;
pub mod lanes;
pub mod tangents;
pub mod trig;
pub mod zero;
