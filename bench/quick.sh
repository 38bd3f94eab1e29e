#!/usr/bin/env bash
# Quick mode of every benchmark, for CI: proves that each still builds and runs end to end
# (criterion benches once each, the step-cost report, the native composed loop, the
# work-precision and Python composed-loop scripts on short runs). Asserts nothing about time.
# Needs the packaged FMUs (cargo run --release -p fmu-build) and the venv (tests/setup-env.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-.venv/bin/python}
# `cargo test --release --workspace` runs the criterion target once per benchmark (test mode) and
# shares the release artifacts that `cargo test --workspace --release` already built (cargo resolves
# features per invocation: `-p rustfmu-bench` alone, or `cargo run`, would build the dependency tree
# again with other features); `cargo bench` would rebuild everything under the bench profile
# (about 3 minutes on 2 cores). The report binaries are the ones that build made.
cargo test --release --workspace --no-run -q
cargo test --release --workspace --bench fmu_step
bin=$(cd "${CARGO_TARGET_DIR:-target}/release" && pwd)
"$bin/perf-report" --rounds 1
"$bin/composed-loop" --seconds 0.1 --repeat 1
"$bin/isolation-cost" --seconds 0.1 --repeat 1
"$PY" bench/python/work_precision.py --quick
RUSTFMU_COMPOSED_LOOP="$bin/composed-loop" "$PY" bench/python/composed_loop.py --quick
"$PY" bench/python/study_throughput.py --quick
"$PY" bench/python/step_bound.py --quick
