#!/usr/bin/env bash
# The documentation's test: the book in docs/ (mdBook) builds, every link and anchor in it
# resolves, README.md's and CHANGELOG.md's relative links and images exist, README.md stays a
# short tour (at most 300 lines), and nothing in the README, the changelog or the book points
# outside the repository. Exits non-zero naming every broken link or rule.
#
#   bash .ci/docs-test.sh        (the book lands in target/book/; open target/book/index.html)
#
# Needs Rust (cargo) and the .venv of .ci/setup-python.sh (run here if missing). Installs, pinned:
# mdBook into target/tools/ (cargo install --debug, ~50 s of build on 2 cores the first time;
# then skipped) and LinkChecker into .venv (a few seconds). LinkChecker checks the built HTML on
# disk with external links off: no network is needed after the installs.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
root="$PWD"

mdbook_version=0.5.4       # crates.io; built without its `serve` and `watch` features
linkchecker_version=10.6.0 # PyPI
tools="$root/target/tools"
mdbook="$tools/bin/mdbook"
book="$root/target/book"
py="$root/.venv/bin/python"

failures=()
fail() { failures+=("$*"); echo "docs test: FAIL: $*"; }
step() { printf '\n== %s  [%ds]\n' "$*" "$SECONDS"; }

step "text rules: README length, nothing pointing outside the repository"
lines=$(wc -l <README.md)
if [ "$lines" -gt 300 ]; then
    fail "README.md has $lines lines; at most 300 (move the detail into docs/)"
else
    echo "README.md: $lines lines (at most 300)"
fi
# The design of record lives in docs/; nothing may send a reader to files outside the repository.
# The whole repository is searched (code comments cite the conventions too), this script aside.
if outside=$(git grep -nE 'DESIGN\.md|DESIGN §|DESIGN section|\.\./shared|shared/|STYLE\.md' -- ':!.ci/docs-test.sh'); then
    while IFS= read -r hit; do fail "points outside the repository: $hit"; done <<<"$outside"
else
    echo "no mention of DESIGN.md, STYLE.md or shared/ anywhere in the repository"
fi

step "book structure: every chapter in SUMMARY.md, every job page ends with its generated options"
# A chapter missing from SUMMARY.md would never be rendered, so its links never checked.
while IFS= read -r page; do
    rel="${page#docs/src/}"
    grep -qF "($rel)" docs/src/SUMMARY.md || fail "$page is not listed in docs/src/SUMMARY.md"
done < <(find docs/src -name '*.md' ! -name SUMMARY.md ! -path 'docs/src/jobs/options/*' | sort)
for page in docs/src/jobs/*.md; do
    job="$(basename "$page" .md)"
    want="{{#include options/$job.md}}"
    [ "$(grep -v '^[[:space:]]*$' "$page" | tail -n 1)" = "$want" ] ||
        fail "$page does not end with the line $want"
    [ -f "docs/src/jobs/options/$job.md" ] || fail "docs/src/jobs/options/$job.md is missing"
done

step "README.md and CHANGELOG.md: relative links and images exist"
[ -x "$py" ] || bash .ci/setup-python.sh
if ! "$py" - README.md CHANGELOG.md <<'EOF'; then
import re
import sys
from pathlib import Path

FENCE = re.compile(r"^\s*(```|~~~)")
LINK = re.compile(r"!?\[(?:[^\]\\]|\\.)*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
IMG = re.compile(r"<img\s[^>]*src=\"([^\"]+)\"")


def text_lines(path):
    """(line number, text) outside fenced code blocks, inline code spans removed."""
    inside = False
    for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if FENCE.match(line):
            inside = not inside
            continue
        if not inside:
            yield n, re.sub(r"`[^`]*`", "", line)


def slug(heading):
    """GitHub's (and mdBook's) anchor of a heading."""
    h = re.sub(r"`|\*\*|__", "", heading.strip().lower())
    h = re.sub(r"[^\w\- ]", "", h)
    return h.replace(" ", "-")


def anchors(path):
    return {slug(t[1].lstrip("#")) for t in text_lines(path) if re.match(r"#{1,6}\s", t[1])}


bad = 0
for name in sys.argv[1:]:
    source = Path(name)
    for n, line in text_lines(source):
        for target in LINK.findall(line) + IMG.findall(line):
            if re.match(r"[a-z][a-z0-9+.-]*:", target):  # https:, mailto:: not checked here
                continue
            file, _, anchor = target.partition("#")
            dest = (source.parent / file) if file else source
            if not dest.exists():
                print(f"{name}:{n}: broken link `{target}`: {dest} does not exist")
                bad += 1
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                print(f"{name}:{n}: broken link `{target}`: no heading `#{anchor}` in {dest}")
                bad += 1
    print(f"{name}: relative links and images checked")
sys.exit(1 if bad else 0)
EOF
    fail "README.md or CHANGELOG.md has broken relative links (listed above)"
fi

step "mdBook $mdbook_version (pinned, in target/tools/)"
if [ -x "$mdbook" ] && [ "$("$mdbook" --version)" = "mdbook v$mdbook_version" ]; then
    echo "already installed: $("$mdbook" --version)"
else
    # --debug: unoptimised, it builds this book in 1.5 s instead of 0.3 s, with the same bytes,
    # and compiles in half the time (2-core Zen 3: 49 s and 88 s of CPU instead of 94 s and
    # 179 s of CPU).
    cargo install mdbook --version "$mdbook_version" --locked --no-default-features \
        --features search --root "$tools" --debug
fi

step "LinkChecker $linkchecker_version (pinned, in .venv)"
if [ "$("$py" -c 'import importlib.metadata as m; print(m.version("linkchecker"))' 2>/dev/null)" = "$linkchecker_version" ]; then
    echo "already installed: linkchecker $linkchecker_version"
elif [ -x "$root/.venv/bin/uv" ]; then
    "$root/.venv/bin/uv" pip install --quiet --python "$py" "linkchecker==$linkchecker_version"
else
    "$py" -m pip install --quiet --disable-pip-version-check "linkchecker==$linkchecker_version"
fi

step "build the book into target/book/"
rm -rf "$book"
log="$(mktemp)"
if ! "$mdbook" build docs -d "$book" >"$log" 2>&1; then
    cat "$log"
    fail "mdbook build failed"
elif grep -E 'ERROR|WARN' "$log"; then
    fail "mdbook build reported the errors or warnings above"
else
    echo "built: $(find "$book" -name '*.html' | wc -l) HTML pages"
fi
rm -f "$log"
# An include that failed leaves its directive in the page.
if [ -d "$book" ] && unresolved=$(grep -rlF '{{#' "$book" --include='*.html'); then
    fail "unresolved mdBook directives in: $unresolved"
fi

step "every link and anchor of the built book (LinkChecker, on disk, external links off)"
if [ -f "$book/index.html" ]; then
    # LinkChecker run as root switches to user nobody, who may not be able to read a clone in
    # /root: it checks a world-readable copy, and runs with its privilege drop turned off (it
    # reads only these local files; external links are not fetched).
    copy="$(mktemp -d)"
    cp -r "$book" "$copy/book"
    chmod -R a+rX "$copy"
    config="$copy/linkcheckerrc"
    printf '[filtering]\ncheckextern=0\n[AnchorCheck]\n' >"$config"
    out="$copy/linkchecker.txt"
    # print.html repeats every chapter on one page (the chapters' own links are checked);
    # skipping it saves most of the time.
    if "$py" - --no-status -f "$config" --ignore-url='/print\.html$' "$copy/book/index.html" \
        >"$out" 2>&1 <<'EOF'; then
import sys

from linkcheck.command import linkchecker as command

command.drop_privileges = lambda: None
sys.argv[0] = "linkchecker"
sys.exit(command.linkchecker())
EOF
        grep -E "^That's it" "$out" || true
    else
        # The failing links with their pages; page X.html is docs/src/X.md.
        sed -n '/^URL  *`/,/^Statistics:/p' "$out" | grep -v '^Statistics:' |
            sed -e "s|file://$copy/book|target/book|g" -e "s|$copy/book|target/book|g"
        grep -E "^That's it" "$out" || tail -n 20 "$out"
        fail "the book has broken links or anchors (listed above; page X.html is docs/src/X.md)"
    fi
    rm -rf "$copy"
else
    fail "no built book to check"
fi

step "done"
if [ "${#failures[@]}" -ne 0 ]; then
    echo "docs test: ${#failures[@]} failure(s):"
    printf '  - %s\n' "${failures[@]}"
    exit 1
fi
echo "docs test: the book builds, every link resolves, the README is $lines lines"
