//! FMI 2.0 for model exchange and co-simulation: the C types of the standard's headers, one
//! instance's state machine in safe Rust, and the C functions around it.

mod abi;
mod instance;
mod types;
