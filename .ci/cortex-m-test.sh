#!/usr/bin/env bash
# twv's kernels on a microcontroller (crate twv-firmware): the no_std build for a Cortex-M4F
# (thumbv7em-none-eabihf) run under QEMU's system emulation of Arm's mps2-an386 board, against
# the same computation on the host, and the C API from a C program.
#
# 1. The case: vehicle8 at the study's tilt under the library's default PD law (gains and
#    setpoint read from `twv simulate --print-settings`), 2000 RK4 steps of 1 ms.
# 2. Host: the case in Rust (examples/case.rs) and in C (c/check.c, compiled with gcc against
#    include/twv_firmware.h and the host's libtwv_firmware.a).
# 3. Cortex-M4F: firmware/qemu built with `-Z build-std=core` (the Rust toolchain here has no
#    thumbv7em standard library; Debian's rust-src, .ci/rust-src.sh), linked by rust-lld, run by
#    qemu-system-arm with semihosting and -icount shift=0 (one instruction = 1 ns of virtual
#    time, which SysTick counts).
# Every result must have the same bits on all three; the emulator's instruction counts per RK4
# step and per f, and the code size, are printed (an estimate of cycles, named as such).
#
#   bash .ci/cortex-m-test.sh [path/to/twv]   (default target/debug/twv; the host's case and
#                                              static library from the same folder)
#   bash .ci/cortex-m-test.sh --install-only  (qemu-system-arm and the library source only)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

if ! command -v qemu-system-arm >/dev/null; then
    if [ "$(id -u)" -ne 0 ]; then
        echo "Cortex-M test: needs root to install qemu-system-arm"
        exit 1
    fi
    apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        qemu-system-arm >/dev/null
fi
bash .ci/rust-src.sh
[ "${1:-}" = "--install-only" ] && exit 0
twv="$(realpath "${1:-target/debug/twv}")"
[ -x "$twv" ] || { echo "Cortex-M test: no twv at $twv (build it first)"; exit 1; }

# The case, from the library's defaults.
read -r kp kd amplitude f_max < <("$twv" simulate --print-settings | python3 -c '
import json, sys
pitch = json.load(sys.stdin)["controller"]["pitch"]
setpoint = pitch["setpoint"]
amplitude = setpoint["amplitude"] if setpoint["kind"] == "sine" else 0.0
f_max = pitch["saturation"] if pitch["saturation"] is not None else "inf"
print(pitch["gains"]["kp"], pitch["gains"]["kd"], amplitude, f_max)')
x0=(0.1 0 0 0 0 0 0 0)
u=(20 0.5)
h=0.001
steps=2000
join() { local IFS=,; echo "$*"; }
case_text="x=$(join "${x0[@]}") u=$(join "${u[@]}") kp=$kp kd=$kd amplitude=$amplitude f_max=$f_max h=$h steps=$steps"
echo "case: $case_text"

work="$(mktemp -d /tmp/twv-cortex-m.XXXXXX)"
trap 'rm -rf "$work"' EXIT

# Host: Rust and C, from the build twv came from (the test command's `cargo build --workspace
# --lib` made both), else built here.
built="$(dirname "$twv")"
if [ ! -x "$built/examples/case" ] || [ ! -f "$built/libtwv_firmware.a" ]; then
    cargo build -q -p twv-firmware --lib --example case
    built=target/debug
fi
"$built/examples/case" "$case_text" >"$work/host.txt"
gcc -std=c11 -O2 -Wall -Wextra -Werror -I firmware/include firmware/c/check.c \
    "$built/libtwv_firmware.a" -lpthread -ldl -lm -o "$work/check"
"$work/check" "$kp" "$kd" "$amplitude" "$f_max" "$h" "$steps" "${x0[@]}" "${u[@]}" >"$work/c.txt"

# Cortex-M4F, the program linted as the workspace is (clippy-driver, -D warnings).
export RUSTC_BOOTSTRAP=1
TWV_CLIPPY_DRIVER="${TWV_CLIPPY_DRIVER:-$(rustup which clippy-driver 2>/dev/null || command -v clippy-driver)}"
export TWV_CLIPPY_DRIVER
elf=target/cortex-m/thumbv7em-none-eabihf/release/twv-firmware-qemu
TWV_FIRMWARE_CASE="$case_text" RUSTC_WORKSPACE_WRAPPER="$PWD/.ci/clippy-rustc" \
    cargo build -q --release --manifest-path firmware/qemu/Cargo.toml \
    -Z build-std=core --target thumbv7em-none-eabihf --target-dir target/cortex-m
timeout 120 qemu-system-arm -M mps2-an386 -nographic -monitor none -semihosting \
    -icount shift=0 -kernel "$elf" >"$work/m4.txt"

failed=0
compare() { # WHAT FILE LINES...
    local what="$1" file="$2"
    shift 2
    for name in "$@"; do
        if [ "$(grep "^$name " "$work/host.txt")" = "$(grep "^$name " "$file")" ] &&
            grep -q "^$name " "$file"; then
            echo "same bits: $name ($what and the host's Rust)"
        else
            echo "DIFFERENT: $name ($what and the host's Rust)"
            failed=1
        fi
    done
}
compare "Cortex-M4F under QEMU" "$work/m4.txt" f jac_x jac_u force rk4 status
compare "C on the host" "$work/c.txt" f rk4 status
grep -q "^status 0$" "$work/host.txt" || { echo "the closed loop did not stay finite"; failed=1; }

# The emulator's counts and the code size.
python3 - "$work/m4.txt" <<'PY'
import sys
words = dict(w.split("=") for w in open(sys.argv[1]).read().split("timing ")[1].split())
n = {k: int(v) for k, v in words.items()}
per_tick = n["calibration_instructions"] / n["calibration_ticks"]
print(f"QEMU -icount: {per_tick:g} instructions per SysTick tick (from a 2-instruction loop)")
print(f"instructions per RK4 step of the closed loop: {n['rk4_ticks'] * per_tick / n['rk4_steps']:.0f}"
      " (an estimate of Cortex-M4F cycles: the emulator counts instructions, not cycles)")
print(f"instructions per f: {n['f_ticks'] * per_tick / n['f_calls']:.0f}")
PY
readelf -SW "$elf" | python3 -c '
import sys
for line in sys.stdin:
    f = line.replace("[ ", "[").split()
    if len(f) > 5 and f[1] in (".text", ".rodata"):
        print(f"firmware image {f[1]}: {int(f[5], 16)} bytes")'
readelf -sW "$elf" | python3 -c '
import re, sys
groups = {"twv (kernels, law, RK4, C API)": 0, "compiler-builtins (double arithmetic, libm)": 0,
          "the rest (parsing the case, formatting, semihosting, start-up)": 0}
names = list(groups)
for f in (line.split() for line in sys.stdin):
    if len(f) == 8 and f[3] == "FUNC":
        size, name = int(f[2]), f[7]
        if name.startswith("twv_") or re.search(r"twv_(generated|firmware\d|kernels|step)", name):
            groups[names[0]] += size
        elif "compiler_builtins" in name or name.startswith("__aeabi"):
            groups[names[1]] += size
        else:
            groups[names[2]] += size
for k, v in groups.items():
    print(f"  code of {k}: {v} bytes")'
exit "$failed"
