//! The `twv` command line: a thin shell that turns the result of `run` into an exit code.

fn main() {
    println!("twv: commands are being written");
}
