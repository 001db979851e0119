#!/usr/bin/env bash
# The standard library's source, which `-Z build-std` compiles for a target the machine's Rust
# has no standard library for (aarch64 in .ci/aarch64-test.sh, thumbv7em-none-eabihf in
# .ci/cortex-m-test.sh): what `rustup component add rust-src` would install, which rustup
# cannot fetch here. Idempotent.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

# Where cargo looks for it: Debian's rust-src of the same version, which carries its
# dependencies vendored (library/vendor).
sysroot="$(rustc --print sysroot)"
if [ ! -f "$sysroot/lib/rustlib/src/rust/library/core/Cargo.toml" ]; then
    version="$(rustc -V | cut -d' ' -f2)"
    case "$version" in
    1.95.0)
        deb="rust-src_1.95.0+dfsg1-2~bpo13+1_all.deb"
        sha256="7b76db5b880a77f9e52975d2baa6209d2f76d2c9c2789515c3088cb960e2c83b"
        ;;
    *)
        echo "rust-src: no pinned Debian rust-src for rustc $version (add its package" \
            "from trixie-backports or sid, and its SHA-256, to $0)"
        exit 1
        ;;
    esac
    cache="$PWD/target/rust-src"
    mkdir -p "$cache"
    if [ ! -f "$cache/$deb" ] || ! echo "$sha256  $cache/$deb" | sha256sum -c --quiet 2>/dev/null; then
        curl -fsS --retry 3 -o "$cache/$deb.part" "https://deb.debian.org/debian/pool/main/r/rustc/$deb"
        echo "$sha256  $cache/$deb.part" | sha256sum -c --quiet
        mv "$cache/$deb.part" "$cache/$deb"
    fi
    rm -rf "$cache/root"
    dpkg-deb -x "$cache/$deb" "$cache/root"
    mkdir -p "$sysroot/lib/rustlib/src"
    ln -sfn "$cache/root/usr/src/rustc-$version" "$sysroot/lib/rustlib/src/rust"
fi
