#!/usr/bin/env bash
# What each link-time optimisation setting costs to build and what it saves in bytes, on the host:
# for each variant (fat LTO = the fmu-release profile; thin LTO; no LTO; fat LTO with opt-level
# "s"), a cold cargo folder of its own under target/profile-costs/: the dependencies with the
# first library (dahlquist-fmu), then pendulum-fmu and controller-fmu, then pendulum-fmu alone
# again (its crate changed): CPU seconds (user + sys) of each, and the libraries' sizes.
# About 4 minutes a variant on 2 idle cores. (Issue 53: what a crate of cargo fmu build costs.)
#
#   bash bench/fmu-profile-costs.sh
set -euo pipefail
cd "$(dirname "$0")/.."
source tests/pyo3-env.sh
mkdir -p target/profile-costs
for v in 'fat:lto="fat"' 'thin:lto="thin"' 'off:lto=false' 'fat-s:lto="fat";opt-level="s"'; do
  name=${v%%:*}
  args=(--config 'profile.var.inherits="release"' --config 'profile.var.strip=true' --config 'profile.var.panic="unwind"')
  IFS=';' read -ra kvs <<< "${v#*:}"
  for kv in "${kvs[@]}"; do args+=(--config "profile.var.$kv"); done
  d=target/profile-costs/$name
  rm -rf "$d"
  build() {
    /usr/bin/time -f "%U %S" -o "$d.time" env CARGO_TARGET_DIR="$d" cargo rustc --profile var "${args[@]}" --lib \
      --crate-type cdylib -p "$1" >"$d.log" 2>&1
    awk -v what="$2" -v n="$name" '{printf "%-6s %-44s %6.1f CPU s\n", n, what, $1 + $2}' "$d.time"
  }
  build dahlquist-fmu "dependencies and dahlquist-fmu"
  build pendulum-fmu "pendulum-fmu (and holonomic)"
  build controller-fmu "controller-fmu"
  touch holonomic/fmus/pendulum/src/lib.rs
  build pendulum-fmu "pendulum-fmu alone"
  for f in "$d"/var/*.so; do printf '%-6s %-44s %9d bytes\n' "$name" "$(basename "$f")" "$(stat -c %s "$f")"; done
done
