//! How benchmarks and the report name the machine: the CPU from /proc/cpuinfo's text on x86-64
//! and aarch64, and the kernels' build in force.

use twv_analysis::machine::{cpu_name, describe};
use twv_kernels::isa;

#[test]
fn x86_names_the_model_with_family_and_model() {
    let text = "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 25\nmodel\t\t: 1\n\
                model name\t: AMD EPYC 7B13\nflags\t\t: fpu avx2\n";
    assert_eq!(cpu_name(text), "AMD EPYC 7B13 (family 25, model 1)");
}

#[test]
fn aarch64_names_the_core_from_its_codes() {
    let text = "processor\t: 0\nBogoMIPS\t: 243.75\nFeatures\t: fp asimd\n\
                CPU implementer\t: 0x41\nCPU architecture: 8\nCPU part\t: 0xd40\n";
    assert_eq!(
        cpu_name(text),
        "aarch64 CPU (Arm Neoverse V1, implementer 0x41, part 0xd40)"
    );
    let other = text.replace("0xd40", "0xfff");
    assert_eq!(
        cpu_name(&other),
        "aarch64 CPU (implementer 0x41, part 0xfff)"
    );
}

#[test]
fn a_text_without_either_is_unknown() {
    assert!(cpu_name("processor: 0\n").starts_with("unknown "));
}

#[test]
fn this_machine_names_the_build_in_force() {
    let text = describe();
    assert!(text.contains(&format!(
        "{} code, kernels: {} build",
        std::env::consts::ARCH,
        isa::current().name()
    )));
    assert!(text.contains("baseline"), "{text}");
}
