//! The case of `twv_firmware::case` on the host: `cargo run -p twv-firmware --example case --
//! "x=... u=... kp=... ..."` prints the bits `.ci/cortex-m-test.sh` compares with the Cortex-M4's.

fn main() {
    let text = std::env::args().nth(1).unwrap_or_default();
    match twv_firmware::case::Case::parse(&text) {
        Ok(case) => {
            let mut out = String::new();
            case.run(&mut out).expect("writing to a String cannot fail");
            print!("{out}");
        }
        Err(bad) => {
            eprintln!("case: cannot read {:?}", bad.0);
            std::process::exit(2);
        }
    }
}
