#!/usr/bin/env bash
# Sizes of one FMU binary (default: the Controller's Windows DLL, its largest) built with each
# profile setting cargo fmu build could use: what docs/platforms.md's "Size" table reports.
# Each variant builds the library alone (`cargo rustc --crate-type cdylib`, as cargo fmu build
# does: an rlib beside it switches link-time optimisation off) into a cargo folder of its own
# under target/size-variants/ (its dependencies too: about a minute a variant on 2 cores).
#
#   bash bench/binary-sizes.sh [PACKAGE] [TARGET]     e.g. controller-fmu x86_64-pc-windows-gnu
#
# Needs the target's linker (tests/setup-env.sh); a target with a glibc suffix or a macOS target
# is built with .venv/bin/cargo-zigbuild.
set -euo pipefail
cd "$(dirname "$0")/.."
source tests/pyo3-env.sh
package=${1:-controller-fmu}
target=${2:-x86_64-pc-windows-gnu}
cargo=(cargo)
if [[ "$target" == *apple-darwin* || "$target" =~ \.[0-9]+\.[0-9]+$ ]]; then
    cargo=(.venv/bin/cargo-zigbuild)
    export PATH="$PWD/.venv/bin:$PATH"
fi
lib=$(echo "$package" | tr - _)
case "$target" in
    *windows*) file="$lib.dll" ;;
    *darwin*) file="lib$lib.dylib" ;;
    *) file="lib$lib.so" ;;
esac
variant() {
    local name=$1
    shift
    local args=(--config 'profile.sizes.inherits="release"')
    for kv in "$@"; do args+=(--config "profile.sizes.$kv"); done
    local dir=target/size-variants/$name
    local started=$SECONDS
    CARGO_TARGET_DIR=$dir "${cargo[@]}" rustc --profile sizes "${args[@]}" --target "$target" --lib --crate-type cdylib \
        -p "$package" >"$dir.log" 2>&1 || { echo "$name: build failed, see $dir.log"; return; }
    printf '%-34s %10d bytes  (%d s with its dependencies)\n' "$name" \
        "$(stat -c %s "$dir/${target%%.[0-9]*}/sizes/$file")" $((SECONDS - started))
}
mkdir -p target/size-variants
echo "$package for $target ($file):"
variant "release" 'lto=false'
variant "strip" 'strip=true' 'lto=false'
variant "strip, thin LTO" 'strip=true' 'lto="thin"'
variant "strip, fat LTO (fmu-release)" 'strip=true' 'lto="fat"'
variant "strip, fat LTO, codegen-units 1" 'strip=true' 'lto="fat"' 'codegen-units=1'
variant "strip, fat LTO, opt-level s" 'strip=true' 'lto="fat"' 'opt-level="s"'
variant "strip, fat LTO, panic abort" 'strip=true' 'lto="fat"' 'panic="abort"'
