#!/usr/bin/env bash
# Runs every test of the project on a fresh machine: installs what they need, checks format and
# lints, builds and packages every FMU (validated by fmu-build and by fmpy), then runs the Rust
# tests and the Python tests that use the packaged FMUs as importers do.
set -euo pipefail
cd "$(dirname "$0")/.."

bash tests/setup-env.sh
export PATH="$PWD/.venv/bin:$PATH"

echo "== cargo fmt --check"
cargo fmt --all --check
echo "== cargo clippy -D warnings"
cargo clippy --workspace --all-targets --release -- -D warnings
echo "== fmu-build (build, package, validate with fmpy)"
cargo run --release -p fmu-build -- build --python .venv/bin/python
echo "== fmutool -check (fmu-manipulation-toolbox) on every FMU"
for fmu in target/fmu/*.fmu; do fmutool -input "$fmu" -check; done
echo "== modelDescription/ is up to date"
cargo run --release -p fmu-build -- xml --check
echo "== Rust tests (with the FMI 2.0 conformance suite, tests/conformance, on every FMU in target/fmu)"
cargo test --workspace --release
echo "== Python tests"
python -m pytest tests/python -q -p no:cacheprovider
echo "== Benchmarks still run (quick mode, no timing asserted)"
bash bench/quick.sh
