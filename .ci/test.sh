#!/usr/bin/env bash
# Every test of twv, from a fresh clone: Python modeling (ruff, pytest, IR freshness), then Rust
# (fmt, clippy, tests). Installs what it needs itself (.venv/ with pinned versions).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
step() { printf '\n== %s  [%ds]\n' "$*" "$SECONDS"; }
# The children's CPU seconds (user + system) in the output of bash's `times`, saved to FILE: its
# second line, as 1m2.345s 0m0.678s. (`times` itself must run in the shell measured, not in a
# command substitution, which is a fresh process.)
children_cpu() { # FILE
    awk 'NR == 2 { for (i = 1; i <= 2; i++) { split($i, a, "m"); sub("s", "", a[2]);
        n += a[1] * 60 + a[2] } printf "%.0f", n }' "$1"
}
# Runs COMMAND in a subshell and appends its wall and CPU seconds (user + system of every process
# it waited for) to target/step-times.txt, which the last step prints: each run says where its
# time went. Returns COMMAND's status.
timed() { # NAME COMMAND...
    local name="$1"
    shift
    (
        start=$SECONDS
        status=0
        "$@" || status=$?
        record="target/.times.$BASHPID"
        times >"$record"
        cpu=$(children_cpu "$record")
        rm -f "$record"
        printf '%6d s CPU %6d s wall  %s\n' "$cpu" $((SECONDS - start)) "$name" \
            >>target/step-times.txt
        exit "$status"
    )
}
# Waits for a test started in the background, prints its log, and stops here if it failed.
finish() { # NAME PID LOG
    local status=0
    wait "$2" || status=$?
    cat "$3"
    if [ "$status" -ne 0 ]; then
        echo "$1 failed (exit $status)"
        exit "$status"
    fi
}

step "machine"
# Which kernels the bit-for-bit ISA tests can compare here (they say so when they cannot).
grep -m1 "model name" /proc/cpuinfo || true
if grep -qw avx512f /proc/cpuinfo && grep -qw avx512vl /proc/cpuinfo; then
    echo "AVX-512F/VL: yes (the AVX-512 builds are compared with the baseline builds)"
else
    echo "AVX-512F/VL: no (the AVX-512 comparisons are skipped and say so)"
fi

mkdir -p target
: >target/step-times.txt
step "python environment (.venv, pinned)"
timed "python environment" bash .ci/setup-python.sh
py=.venv/bin/python

step "ruff"
.venv/bin/ruff check modeling analysis/benches analysis/serve/browser python
.venv/bin/ruff format --check modeling analysis/benches analysis/serve/browser python

# Debian's Slurm and MUNGE for the cluster test, Chromium with its WebDriver for the browser
# test, the aarch64 cross tools (gcc, qemu, the standard library's source) for the NEON test and
# QEMU's Arm system emulator for the Cortex-M test at the end, installed while Rust builds (one
# after the other: apt holds a lock).
step "Slurm, MUNGE, Chromium, ChromeDriver, aarch64 and Cortex-M packages (in the background)"
( timed "system packages" bash -c 'bash .ci/slurm-test.sh --install-only && bash .ci/browser-test.sh --install-only &&
    bash .ci/aarch64-test.sh --install-only && bash .ci/cortex-m-test.sh --install-only' ) \
    >target/slurm-install.log 2>&1 &
slurm_install_pid=$!

# The book (mdBook, installed pinned into target/tools the first time, ~90 s of one core)
# and its links: it needs nothing of the Rust build, so it starts first, beside the builds.
step "docs: the book builds and every link resolves (in the background)"
( timed docs bash .ci/docs-test.sh >target/docs-test.log 2>&1 ) &
docs_pid=$!

step "pytest modeling/"
# Two workers, each test module on one (its derived models are cached per process): ~37 s -> ~24 s.
timed "pytest modeling" "$py" -m pytest -q -p no:cacheprovider -n 2 --dist loadfile modeling/tests

step "IR freshness (generated/ir is what the modeling code derives today)"
"$py" -m twv_modeling check
# vehicles/bicycles is what the pinned bicycleparameters' data set converts to today.
"$py" -m twv_modeling bicycles --check

# The two workspaces outside the main one (fuzz/, firmware/qemu/) keep lock files of their own,
# which go stale when a crate they use gains a dependency: checked here, in a second, rather than
# by the background fuzz step twenty minutes in.
step "lock files of fuzz/ and firmware/qemu/ are current (cargo metadata --locked)"
for manifest in Cargo.toml fuzz/Cargo.toml firmware/qemu/Cargo.toml; do
    cargo metadata --locked --format-version 1 --manifest-path "$manifest" >/dev/null
done

step "cargo fmt --check"
cargo fmt --all --check
cargo fmt --manifest-path fuzz/Cargo.toml --check
cargo fmt --manifest-path firmware/qemu/Cargo.toml --check

# One build of every target, linted: clippy-driver compiles the workspace crates with -D warnings
# (the lints of `cargo clippy --workspace --all-targets -- -D warnings`, see .ci/clippy-rustc), so
# the code is linted and built once instead of checked and then built. In the release profile,
# tests too: the Python package in .venv must be the optimised build, and maturin below then
# reuses every compiled crate of this build (18 s) instead of building the analysis stack a
# second time (10-13 min on 2 cores when the tests were built in the dev profile). `--lib`
# builds the libraries no test links: the export runtime (libtwv_export.so) and the firmware's
# static library.
step "cargo build of every target in the release profile, with clippy's lints (-D warnings)"
TWV_CLIPPY_DRIVER="$(rustup which clippy-driver 2>/dev/null || command -v clippy-driver)"
export TWV_CLIPPY_DRIVER
export RUSTC_WORKSPACE_WRAPPER="$PWD/.ci/clippy-rustc"
profile=(--profile release)
timed "linted build" cargo test --workspace --no-run "${profile[@]}"
step "cargo build of the libraries no test links (export runtime, firmware) and the benchmarks"
timed "libraries, benchmarks" cargo build --workspace --lib --benches "${profile[@]}"
twv="$PWD/target/release/twv"

# The README's main command builds only `twv`; twv-unify (unify/Cargo.toml) gives that build the
# feature set of the workspace's, so it finds every crate built above. Were a feature to differ,
# it would compile the analysis crate again (~4 min) on a fresh clone: checked here, in seconds.
step "the main command's build finds everything built (one feature set, unify/)"
main_build="$(cargo build --release -p twv-cli --bin twv 2>&1)" || { echo "$main_build"; exit 1; }
if grep -q "Compiling" <<<"$main_build"; then
    echo "$main_build"
    echo "the main command's build compiled crates again: a dependency's features differ between"
    echo "it and the workspace's build; add them to unify/Cargo.toml (see its comment)"
    exit 1
fi

# trybuild's compile-fail case builds the proc-macro's dependencies in a target folder of its
# own (~50 s of one core): it runs in the background beside the doc tests and the Python
# package, where a core is idle, instead of inside nextest. Both runs name what they ran. Both
# select from the whole workspace: `-p twv-macros` alone resolved other features for the
# proc-macro's dependencies and compiled seven of them and twv-macros again (19 s).
step "cargo nextest (every test binary, in parallel; the compile-fail case in the background)"
compile_fail='test(=macro_errors_are_compile_errors)'
timed nextest cargo nextest run --workspace --cargo-profile release --no-fail-fast \
    -E "not $compile_fail"
( timed "compile-fail" cargo nextest run --workspace --cargo-profile release -E "$compile_fail" \
    >target/compile-fail-test.log 2>&1 ) &
compile_fail_pid=$!

# The cluster mostly waits on its daemons: it runs beside the doc tests and the Python package.
step "a real single-node Slurm cluster: sbatch --array shards of a sweep (in the background)"
if ! wait "$slurm_install_pid"; then
    cat target/slurm-install.log
    echo "installing Slurm, MUNGE, Chromium, the aarch64 cross tools or QEMU for Arm failed"
    exit 1
fi
( timed Slurm bash .ci/slurm-test.sh "$twv" >target/slurm-test.log 2>&1 ) &
slurm_pid=$!

# The browser test mostly waits on Chromium and the server: beside them too.
step "twv serve in a real browser: headless Chromium through WebDriver (in the background)"
( timed browser bash .ci/browser-test.sh "$twv" >target/browser-test.log 2>&1 ) &
browser_pid=$!

# The aarch64 cross build and its emulated tests: beside the doc tests and the Python package,
# which leave a core idle much of the time.
step "aarch64: cross-build for aarch64, run the NEON tests under qemu (in the background)"
( timed aarch64 bash .ci/aarch64-test.sh "$twv" >target/aarch64-test.log 2>&1 ) &
aarch64_pid=$!

# The firmware crate built for a Cortex-M4F and run under QEMU's system emulation: beside them.
step "Cortex-M4F under QEMU: the firmware's results have the host's bits (in the background)"
( timed Cortex-M bash .ci/cortex-m-test.sh "$twv" >target/cortex-m-test.log 2>&1 ) &
cortex_m_pid=$!

step "cargo test --doc"
timed "doc tests" cargo test --workspace --doc "${profile[@]}"

# The fuzz targets, built with coverage instrumentation into target/fuzz/ (a build of their own),
# a fixed number of runs each: beside the Python package too.
step "fuzzing: every fuzz target, a fixed number of runs from its corpus (in the background)"
( TWV_FUZZ_RUNS=100000 timed fuzzing bash .ci/fuzz.sh >target/fuzz-test.log 2>&1 ) &
fuzz_pid=$!

step "python package: the release build of the extension into .venv (maturin), pytest python/tests"
# --release: the package a user finds in .venv is the optimised one (a debug build ran a 20 x 20
# map ~20 times slower than the CLI); its tests check that it is (TWV_EXPECT_PROFILE). It reuses
# the release build above. --uv: the .venv's pinned uv installs the extension (pip resolving its
# dependencies took ~20 s).
PATH="$PWD/.venv/bin:$PATH" VIRTUAL_ENV="$PWD/.venv" timed "python package build" \
    .venv/bin/maturin develop --release --uv --quiet -m python/Cargo.toml
TWV_BIN="$twv" TWV_EXPECT_PROFILE=release timed "pytest python" \
    "$py" -m pytest -q -p no:cacheprovider python/tests

step "the browser test: the page's plots and margins are the CLI's for the dragged gains (its log)"
finish "the browser test" "$browser_pid" target/browser-test.log

step "trybuild: every defect of an IR file is a compile error naming it (its log)"
finish "the compile-fail test" "$compile_fail_pid" target/compile-fail-test.log

step "the Slurm cluster test: merged shards = unsharded map (its log)"
finish "the Slurm cluster test" "$slurm_pid" target/slurm-test.log

step "docs: the book and its links (its log)"
finish "the docs test" "$docs_pid" target/docs-test.log

step "fuzzing: no crash, hang or out-of-memory (its log)"
finish "the fuzz test" "$fuzz_pid" target/fuzz-test.log

step "aarch64 under qemu: the NEON lanes kernel has the one-point bits, twv the same bytes (its log)"
finish "the aarch64 test" "$aarch64_pid" target/aarch64-test.log

step "Cortex-M4F under QEMU: same bits as the host, instructions per RK4 step (its log)"
finish "the Cortex-M test" "$cortex_m_pid" target/cortex-m-test.log

step "where the time went (wall and CPU seconds of each step; background steps overlap)"
sort -n -r target/step-times.txt
times >target/.times.all
echo "the whole run: $SECONDS s wall, $(children_cpu target/.times.all) s CPU"
rm -f target/.times.all

step "done"
