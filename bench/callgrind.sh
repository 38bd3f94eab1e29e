#!/usr/bin/env bash
# Instructions per step of the plant's step, called directly and through the packaged .so's C API,
# counted by callgrind (independent of the machine's load, unlike wall time). Each variant runs
# 1000 and 2000 steps; the difference / 1000 is the cost of one step without the setup. The
# last pair is one evaluation of the right-hand side, in Rust and through model exchange's C API.
# Needs valgrind, the packaged Pendulum, Controller and SampledController FMUs and `cargo build
# --release -p rustfmu-bench`.
set -euo pipefail
cd "$(dirname "$0")/.."
exe=target/release/perf-report
out=$(mktemp -d)
count() {
    valgrind --tool=callgrind --callgrind-out-file="$out/cg.$1.$2" "$exe" --only "$1" --steps "$2" 2>&1 |
        sed -n 's/.*Collected : \([0-9]*\).*/\1/p'
}
declare -A per_step
for v in direct-1ms fmi-1ms direct-round-trip-1ms fmi-round-trip-1ms direct-rhs fmi-derivatives; do
    a=$(count "$v" 1000)
    b=$(count "$v" 2000)
    per_step[$v]=$(((b - a) / 1000))
    echo "$v: ${per_step[$v]} instructions per step"
done
for pair in "1ms" "round-trip-1ms"; do
    d=${per_step[direct-$pair]}
    f=${per_step[fmi-$pair]}
    echo "overhead $pair: $((f - d)) instructions, $(awk "BEGIN { printf \"%+.1f\", ($f / $d - 1) * 100 }") %"
done
d=${per_step[direct-rhs]}
f=${per_step[fmi-derivatives]}
echo "overhead of fmi2SetContinuousStates + fmi2GetDerivatives over one right-hand side: $((f - d)) instructions"
# A tick of the SampledController's clock (FMI 3.0) against the same sample of the 2.0 Controller
# with sampled = true (target/release/clock-tick; both give the same torques).
tick() {
    valgrind --tool=callgrind --callgrind-out-file="$out/cg.tick.$1.$2" target/release/clock-tick --variant "$1" --ticks "$2" 2>&1 |
        sed -n 's/.*Collected : \([0-9]*\).*/\1/p'
}
for v in clocked sampled-2.0; do
    a=$(tick "$v" 1000)
    b=$(tick "$v" 2000)
    per_step[$v]=$(((b - a) / 1000))
    echo "tick $v: ${per_step[$v]} instructions per tick"
done
echo "overhead of the clock (fmi3EnterEventMode, fmi3SetClock, fmi3UpdateDiscreteStates, fmi3EnterStepMode): $((per_step[clocked] - per_step[sampled-2.0])) instructions per tick"
echo "profiles (callgrind_annotate FILE): $out"
