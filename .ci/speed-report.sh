#!/usr/bin/env bash
# Every speed table of the README, measured on this machine, in one file: the kernels against
# both C peers for each build this CPU runs (and the study preset's spectrum against its
# dependent-chain floor), the JIT against compiled and interpreted code, and the 100 × 100
# max-Lyapunov map for each lanes build, and the bicycle's steer map against python-control.
# Each benchmark names the CPU and the builds it ran and
# those it could not. What to run on a CPU the README has no figures for (an AVX2-only Zen 3,
# an aarch64 server):
#
#   bash .ci/speed-report.sh        # -> target/speed/<UTC time>.txt (68 s of benchmarks on
#                                   #    the 2-core Intel Xeon VM, after a release build)
#
# Needs Rust and python3 (the kernel bench's C peers come from CasADi in .venv, set up here) and
# a C compiler. Not part of the test command: timings are never tests. Exits non-zero if any
# benchmark's own checks failed (the kernels' correctness gates, the same spectrum on every
# build, the map's settled-tail tolerance), after running the others.
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash .ci/setup-python.sh || { echo "speed report: setting up .venv failed"; exit 1; }
out="target/speed/$(date -u +%Y%m%dT%H%M%SZ).txt"
# Written as .part and renamed when every benchmark has run: an interrupted report is never
# mistaken for a whole one.
part="$out.part"
mkdir -p target/speed && : >"$part" || { echo "speed report: cannot write $part"; exit 1; }
failed=()

# Runs one benchmark command, its output into the report, and notes a failure.
bench() { # NAME [VAR=VALUE...] COMMAND...
    local name="$1"
    shift
    printf '\n## %s\n\n$ %s\n\n' "$name" "$*" | tee -a "$part"
    if ! env "$@" 2>&1 | tee -a "$part"; then
        failed+=("$name")
    fi
}

{
    echo "# twv speed report"
    echo
    echo "- commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)$(git diff --quiet 2>/dev/null || echo ' (with local changes)'), $(date -u '+%Y-%m-%d %H:%M UTC')"
    echo "- $(rustc -V), $(uname -m), $(nproc) CPUs, load average $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$part"

bench "kernels against both C peers, each build; the preset against its floor" \
    TWV_BENCH_SAMPLES=31 cargo bench -q -p twv-bench --bench kernels
# With the bicycle's CasADi C (the peer of its JIT; ~20 s of gcc the first time).
bench "the JIT against compiled and interpreted code, the bicycle's against CasADi's C" \
    TWV_BENCH_SAMPLES=31 cargo bench -q -p twv-bench --features bicycle-peer --bench jit
bench "the 100 × 100 max-Lyapunov map, each lanes build" \
    TWV_MAP_ROUNDS=2 cargo bench -q -p twv-analysis --bench map
# The bicycle's steer map from Python and the CLI against python-control and NumPy: the
# optimised extension into .venv first (it reuses the release build).
if cargo build -q --release -p twv-cli &&
    PATH="$PWD/.venv/bin:$PATH" VIRTUAL_ENV="$PWD/.venv" .venv/bin/maturin develop --release \
        --uv --quiet -m python/Cargo.toml; then
    bench "the bicycle's 100 × 100 steer map against python-control and NumPy" \
        PYTHONPATH=modeling .venv/bin/python python/benches/steer_map_peers.py
else
    failed+=("the build of twv and its Python package for the steer-map benchmark")
fi

mv "$part" "$out"
echo
if [ "${#failed[@]}" -ne 0 ]; then
    echo "speed report: written to $out; checks FAILED in: ${failed[*]}"
    exit 1
fi
echo "speed report: written to $out (every benchmark's checks held)"
