#!/usr/bin/env bash
# The real-browser test of `twv serve`: installs Debian's chromium and chromium-driver if missing
# (root: CI runs as root), then runs analysis/serve/browser/ with the .venv's pinned selenium
# against the given twv binary. The screenshot lands in target/browser/.
#
#   bash .ci/browser-test.sh [path/to/twv]      (default target/debug/twv)
#   bash .ci/browser-test.sh --install-only     (the packages only; the test command runs this
#                                               in the background while Rust builds)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then
    if [ "$(id -u)" -ne 0 ]; then
        echo "browser test: chromium and chromium-driver are missing and installing them needs root"
        exit 1
    fi
    apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        chromium chromium-driver >/dev/null
fi
[ "${1:-}" = "--install-only" ] && exit 0
TWV_BIN="$(realpath "${1:-target/debug/twv}")" .venv/bin/python -m pytest -q -p no:cacheprovider \
    analysis/serve/browser
