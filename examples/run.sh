#!/usr/bin/env bash
# The main job: build and package every FMU, then run the demo simulations through fmpy.
# Results go to out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tests/setup-env.sh
cargo run --release -p fmu-build -- build --python .venv/bin/python
mkdir -p out
.venv/bin/python examples/pendulum_open_loop.py --out out
