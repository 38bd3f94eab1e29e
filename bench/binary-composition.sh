#!/usr/bin/env bash
# What an FMU binary is made of: the code (.text symbols) of one FMU crate's library, built as
# `cargo fmu build` builds it (profile fmu-release) but without `strip`, summed by where it comes
# from (std's backtrace symbolizer, std's formatting and panics, the rustfmu runtime and its FMI 2.0
# and 3.0 layers, nalgebra, serde, the model). For the host, in target/size-variants/composition/
# (about a minute on 2 cores with its dependencies).
#
#   bash bench/binary-composition.sh [PACKAGE]       e.g. dahlquist-fmu (the default), pendulum-fmu
set -euo pipefail
cd "$(dirname "$0")/.."
source tests/pyo3-env.sh
package=${1:-dahlquist-fmu}
lib=$(echo "$package" | tr - _)
dir=target/size-variants/composition
mkdir -p target/size-variants
CARGO_TARGET_DIR=$dir cargo rustc --profile fmu-release --config 'profile.fmu-release.strip=false' --lib \
    --crate-type cdylib -p "$package" >"$dir.log" 2>&1 || { echo "build failed, see $dir.log"; exit 1; }
file=$dir/fmu-release/lib$lib.so
echo "$package, $(stat -c %s "$file") bytes unstripped; .text $(size -A "$file" | awk '$1==".text"{print $2}') bytes; .text symbols by origin:"
nm -C --size-sort -S "$file" | python3 -c '
import collections, re, sys
origins = [
    ("std: backtrace symbolizer (gimli, addr2line, miniz_oxide)", r"gimli|addr2line|miniz|rustc_demangle|backtrace|symbolize"),
    ("std, core, alloc: formatting, panics, collections", r"^(std|core|alloc)::|^<(std|core|alloc)::|__rust"),
    ("rustfmu: FMI 3.0 layer", r"fmi3"),
    ("rustfmu: FMI 2.0 layer", r"fmi2"),
    ("rustfmu: core (instances, integrator, events, state)", r"rustfmu"),
    ("nalgebra, simba, matrixmultiply", r"nalgebra|simba|matrixmultiply"),
    ("serde, postcard, crc32fast", r"serde|postcard|crc32"),
]
sums = collections.Counter()
for line in sys.stdin:
    parts = line.split(None, 3)
    if len(parts) < 4 or parts[2] not in "tTrR":
        continue
    size, name = int(parts[1], 16), parts[3]
    sums[next((o for o, p in origins if re.search(p, name)), "the rest (the model, other crates)")] += size
total = sum(sums.values())
for origin, size in sums.most_common():
    print(f"  {size:>9,} bytes {100 * size / total:5.1f} %  {origin}")
'
