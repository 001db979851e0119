#!/usr/bin/env bash
# Coverage-guided fuzzing of the IR reader, the parameter-file reader, the hand-file parser and
# audit, and every job's JSON settings (fuzz/fuzz_targets/), a fixed number of runs each from the
# committed corpus (fuzz/corpus/), so the time is bounded. A crash (panic, abort, stack
# overflow), a hang (libFuzzer's -timeout) or an out-of-memory (-rss_limit_mb) fails the script,
# and the input that did it is kept in target/fuzz/artifacts/<target>/.
#
# libFuzzer through the libfuzzer-sys crate on the pinned stable compiler: SanitizerCoverage is a
# stable codegen option (-Cpasses=sancov-module and its -Cllvm-args), which is all libFuzzer needs
# for its guidance. What needs nightly (cargo fuzz's -Zsanitizer=address) is left out: the code
# fuzzed is safe Rust, where AddressSanitizer finds nothing that a panic does not already show.
#
#   bash .ci/fuzz.sh              # every target, TWV_FUZZ_RUNS runs each (default 4000)
#   bash .ci/fuzz.sh hand_file    # one target
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
runs="${TWV_FUZZ_RUNS:-4000}"
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(ir params hand_file settings)
triple="$(rustc -vV | sed -n 's/^host: //p')"
flags=(
    -Cpasses=sancov-module
    -Cllvm-args=-sanitizer-coverage-level=4
    -Cllvm-args=-sanitizer-coverage-inline-8bit-counters
    -Cllvm-args=-sanitizer-coverage-pc-table
    -Cllvm-args=-sanitizer-coverage-trace-compares
    --cfg fuzzing
)
# --target: the flags then reach the fuzzed code only, not build scripts and proc-macros (which
# could not link the coverage callbacks); --locked: the versions of fuzz/Cargo.lock.
RUSTFLAGS="${flags[*]}" cargo build --locked --release --manifest-path fuzz/Cargo.toml \
    --target "$triple" --target-dir target/fuzz --bins
for t in "${targets[@]}"; do
    new="target/fuzz/corpus/$t"
    artifacts="target/fuzz/artifacts/$t/"
    mkdir -p "$new" "$artifacts"
    started=$SECONDS
    # -seed: the same runs every time (a failure reproduces); new inputs go to target/, the
    # committed corpus is only read.
    if ! "target/fuzz/$triple/release/$t" -runs="$runs" -seed=1 -timeout=10 -rss_limit_mb=2048 \
        -max_len=65536 -artifact_prefix="$artifacts" -print_final_stats=1 \
        "$new" "fuzz/corpus/$t" >"target/fuzz/$t.log" 2>&1; then
        tail -40 "target/fuzz/$t.log"
        echo "fuzz target $t failed: the input is in $artifacts"
        exit 1
    fi
    execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "target/fuzz/$t.log" | tail -1)"
    echo "fuzz $t: ${execs:-?} runs in $((SECONDS - started)) s, no crash, hang or out-of-memory"
done
