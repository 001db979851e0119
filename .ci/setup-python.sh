#!/usr/bin/env bash
# Create (once) the git-ignored virtual environment .venv/ with the pinned modeling tools, the
# twv_modeling package importable from modeling/, and the tools that build and test the twv
# Python package (python/requirements.txt). Idempotent; re-installs when the pins change.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="$root/.venv"
stamp="$venv/.twv-requirements"
if [[ ! -x "$venv/bin/python" ]]; then
    python3 -m venv "$venv"
fi
uv_pin="uv==0.13.9"
pins="$uv_pin
$(cat "$root/modeling/requirements.txt" "$root/python/requirements.txt" \
    "$root/analysis/serve/browser/requirements.txt")"
if [[ "$pins" != "$(cat "$stamp" 2>/dev/null)" ]]; then
    # uv (pinned) resolves and installs the pins in parallel: ~10 s on a fresh machine where
    # pip took ~50 s, the longest step before the Rust build.
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "$uv_pin"
    "$venv/bin/uv" pip install --quiet --python "$venv/bin/python" \
        -r "$root/modeling/requirements.txt" -r "$root/python/requirements.txt" \
        -r "$root/analysis/serve/browser/requirements.txt"
    # Make twv_modeling importable from the source tree (what an editable install does, without
    # needing a build backend).
    site="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
    echo "$root/modeling" > "$site/twv_modeling.pth"
    printf '%s' "$pins" > "$stamp"
fi
