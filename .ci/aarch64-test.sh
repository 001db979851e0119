#!/usr/bin/env bash
# The NEON build of the lanes kernel (and the JIT's aarch64 code) without an aarch64 machine:
# cross-compiles the kernels' tests and the bit-for-bit ISA and JIT tests for
# aarch64-unknown-linux-gnu and runs them under qemu's user-mode emulator (same IEEE arithmetic
# as the hardware: what is checked is bits, not speed). The machine's Rust toolchain has no aarch64 standard library and rustup cannot fetch
# one here, so `-Z build-std` compiles it from Debian's source package of the same Rust version
# (pinned below by version and SHA-256); RUSTC_BOOTSTRAP=1 lets the stable compiler take the
# -Z flag. Installs (root) Debian's aarch64 gcc (the linker), its libc and qemu-user-static.
#
# Then the same jobs through both CPUs' `twv` (x86-64's from the test command's build, aarch64's
# cross-built, emulated): the study's Lyapunov spectrum and a max-Lyapunov map must write the
# same bytes on both (JSON, CSV, SVG, PNG; the map through the NEON lanes kernel here and the
# AVX-512 or AVX2 one there).
#
#   bash .ci/aarch64-test.sh [path/to/x86-64 twv]   (default target/debug/twv; install if
#                                                    missing, build, run)
#   bash .ci/aarch64-test.sh --install-only         (packages and the library source only)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

target=aarch64-unknown-linux-gnu
if ! command -v aarch64-linux-gnu-gcc >/dev/null || ! command -v qemu-aarch64-static >/dev/null; then
    if [ "$(id -u)" -ne 0 ]; then
        echo "aarch64 test: needs root to install gcc-aarch64-linux-gnu and qemu-user-static"
        exit 1
    fi
    apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user-static >/dev/null
fi

# The standard library's source for `-Z build-std` (shared with the Cortex-M test).
bash .ci/rust-src.sh
[ "${1:-}" = "--install-only" ] && exit 0
native="$(realpath "${1:-target/debug/twv}")"
[ -x "$native" ] || { echo "aarch64 test: no x86-64 twv at $native (build it first)"; exit 1; }

export RUSTC_BOOTSTRAP=1
# No debug info: these binaries are only run (~10 % less build time). No incremental caches:
# nothing else builds in this target folder (twv-analysis 75 instead of 81 s).
export CARGO_PROFILE_DEV_DEBUG=0
export CARGO_INCREMENTAL=0
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER="qemu-aarch64-static -L /usr/aarch64-linux-gnu"
# The analysis crate and the test crate unoptimised: what runs here is the kernels (opt-level 3
# in every profile) and a few jobs, and at opt-level 1 those two crates were most of this
# step's build (Zen 3, alone: the analysis crate 149 s instead of 62 s, the test crate 40
# instead of 29 s; the whole step 690 s of CPU).
cross=(-Z build-std --target "$target" --target-dir target/aarch64 --profile dev
    --config 'profile.dev.package."twv-analysis".opt-level=0'
    --config 'profile.dev.package."twv-tests".opt-level=0')
# The kernels: the NEON sincos and gathers against the scalar definitions, the ISA choice.
cargo test "${cross[@]}" -p twv-kernels
# Every shipped model's lanes kernel in its NEON build against the one-point kernel (the tests
# name the x86 builds as not run), and the JIT's aarch64 code (Cranelift's other backend)
# against the interpreter: every operation, J·W written out and looped. Left out for time, as
# they take minutes emulated: the map's metric in lanes (`sweep_lanes::`, 76 s; its NEON parts
# are the lanes kernel above and `lanes::sin_cos`, which the kernels' tests check) and the
# whole-model JIT test (150 s).
# The test crate and the CLI's binary come from one `cargo test` build (the binary as the one
# its own tests run): one feature resolution, so the crates they share are built once (a
# separate `cargo build` of the CLI resolves without dev-dependencies: 2 more minutes).
both=(-p twv-tests -p twv-cli --test all)
cargo test "${cross[@]}" "${both[@]}" --test cli --no-run
cargo test "${cross[@]}" "${both[@]}" -- --nocapture isa:: \
    jit::every_operation_has_the_interpreter_bits \
    jit::written_out_and_looped_jw_have_the_interpreter_bits \
    jit::code_compiled_from_another_ir_is_refused

# Same inputs, same bytes, on either CPU. The map is 4 x 4: two groups of eight lanes, as
# many as the NEON lanes kernel needs to be exercised (8 x 8 took a minute emulated).
emulated=(qemu-aarch64-static -L /usr/aarch64-linux-gnu "target/aarch64/$target/debug/twv")
work="$(mktemp -d /tmp/twv-aarch64.XXXXXX)"
trap 'rm -rf "$work"' EXIT
jobs=(
    "lyap --model vehicle8 --preset paper --x0 0.1,0,0,0,0,0,0,0"
    "sweep --kp 0:8000:4 --kd 0:4000:4 --metric max-lyapunov"
)
failed=0
for i in "${!jobs[@]}"; do
    read -ra job <<<"${jobs[$i]}"
    "$native" --quiet "${job[@]}" --out "$work/x86_64-$i" >/dev/null ||
        { echo "twv ${jobs[$i]} failed on x86-64"; exit 1; }
    "${emulated[@]}" --quiet "${job[@]}" --out "$work/aarch64-$i" >/dev/null ||
        { echo "twv ${jobs[$i]} failed on aarch64 (emulated)"; exit 1; }
    files=$(cd "$work/x86_64-$i" && ls)
    [ -n "$files" ] || { echo "twv ${jobs[$i]}: wrote nothing"; failed=1; }
    for f in $files; do
        if cmp -s "$work/x86_64-$i/$f" "$work/aarch64-$i/$f"; then
            echo "same bytes on x86-64 and aarch64: twv ${jobs[$i]} -> $f"
        else
            echo "DIFFERENT on x86-64 and aarch64: twv ${jobs[$i]} -> $f"
            failed=1
        fi
    done
done
exit "$failed"
