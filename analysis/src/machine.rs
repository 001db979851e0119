//! The machine a figure was measured on, as benchmarks and the report name it: speed differs
//! between CPUs (an AVX-512 Zen 4, an AVX2-only Zen 3, an aarch64 Neoverse), so every timing
//! says which CPU and which build of the kernels produced it.

use twv_kernels::isa;

/// This CPU and the kernels' build in force, e.g. "Intel(R) Xeon(R) Processor (family 6, model
/// 167); x86_64 code, kernels: AVX-512 build (this CPU runs AVX-512, AVX2, baseline)".
pub fn describe() -> String {
    // No /proc/cpuinfo (not Linux): an empty text, which names the CPU as unknown.
    let cpu = cpu_name(&std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default());
    let runs: Vec<&str> = isa::ALL
        .iter()
        .rev()
        .filter(|&&i| isa::available(i))
        .map(|i| i.name())
        .collect();
    // The architecture of this binary too: under an emulator (qemu-user) /proc/cpuinfo is the
    // host's, so only this says that aarch64 code ran on an x86-64 CPU's description.
    format!(
        "{cpu}; {} code, kernels: {} build (this CPU runs {})",
        std::env::consts::ARCH,
        isa::current().name(),
        runs.join(", ")
    )
}

/// The CPU's name from the text of /proc/cpuinfo: x86-64 reports a model name and the family
/// and model numbers; Linux on aarch64 reports no name, only the implementer and part codes
/// (named here for the common server cores, as lscpu does).
pub fn cpu_name(cpuinfo: &str) -> String {
    let field = |key: &str| {
        cpuinfo.lines().find_map(|line| {
            let (k, v) = line.split_once(':')?;
            (k.trim() == key).then(|| v.trim().to_string())
        })
    };
    if let Some(name) = field("model name") {
        return match (field("cpu family"), field("model")) {
            (Some(family), Some(model)) => format!("{name} (family {family}, model {model})"),
            _ => name,
        };
    }
    match (field("CPU implementer"), field("CPU part")) {
        (Some(implementer), Some(part)) => {
            let known = arm_core(&implementer, &part).map_or(String::new(), |n| format!("{n}, "));
            format!("aarch64 CPU ({known}implementer {implementer}, part {part})")
        }
        _ => format!("unknown {} CPU", std::env::consts::ARCH),
    }
}

/// A few aarch64 cores by implementer and part code (Arm's and the clouds' common ones).
fn arm_core(implementer: &str, part: &str) -> Option<&'static str> {
    Some(match (implementer, part) {
        ("0x41", "0xd0c") => "Arm Neoverse N1",
        ("0x41", "0xd40") => "Arm Neoverse V1",
        ("0x41", "0xd49") => "Arm Neoverse N2",
        ("0x41", "0xd4f") => "Arm Neoverse V2",
        ("0x41", "0xd8e") => "Arm Neoverse N3",
        ("0x41", "0xd84") => "Arm Neoverse V3",
        ("0x41", "0xd08") => "Arm Cortex-A72",
        ("0x41", "0xd0b") => "Arm Cortex-A76",
        ("0xc0", "0xac3") => "AmpereOne",
        ("0x61", _) => "Apple",
        _ => return None,
    })
}

/// Which twv this is: what `twv --version` and Python's `twv.build_info()` print.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct BuildInfo {
    /// The crate version.
    pub version: &'static str,
    /// The git commit it was built from (`unknown` outside a repository).
    pub commit: &'static str,
    /// `release` (optimised) or `debug`.
    pub profile: &'static str,
    /// The architecture of the code.
    pub arch: &'static str,
    /// The kernels' instruction set in force (the best this CPU runs, or a `--isa` limit).
    pub isa: &'static str,
    /// Whether models without generated code are compiled to native code (the JIT).
    pub jit: bool,
}

impl BuildInfo {
    /// The build of the calling binary: its `commit` and whether it has the JIT.
    pub fn new(commit: &'static str, jit: bool) -> Self {
        Self {
            version: env!("CARGO_PKG_VERSION"),
            commit,
            profile: if cfg!(debug_assertions) {
                "debug"
            } else {
                "release"
            },
            arch: std::env::consts::ARCH,
            isa: isa::current().name(),
            jit,
        }
    }

    /// One line: `0.1.0 (commit 1a2b3c4d5e6f, release build, x86_64, kernels AVX-512, JIT)`.
    pub fn line(&self) -> String {
        format!(
            "{} (commit {}, {} build, {}, kernels {}, {})",
            self.version,
            self.commit,
            self.profile,
            self.arch,
            self.isa,
            if self.jit { "JIT" } else { "no JIT" }
        )
    }
}
