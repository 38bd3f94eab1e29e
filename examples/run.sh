#!/usr/bin/env bash
# The main job: build and package every FMU (and the SSP files of the composed systems), print the
# paper's numbers as computed, draw Figures 6-8, and run the full composed demo (4 FMUs) through fmpy.
# Results go to out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tests/setup-env.sh
cargo run --release -p fmu-build -- build --python .venv/bin/python
mkdir -p out
cargo run --release --example paper_numbers | tee out/paper_numbers.txt
.venv/bin/python examples/paper_figures.py --out out
.venv/bin/python examples/composed_demo.py --out out
# Parameter studies on a Dask LocalCluster, small grids (the full ones: docs/parameter-studies.md).
rm -f out/study/roa.csv out/study/robust.csv
.venv/bin/python examples/parameter_study.py roa --out out/study --n 15 --no-progress
.venv/bin/python examples/parameter_study.py robust --out out/study --samples 40 --no-progress
