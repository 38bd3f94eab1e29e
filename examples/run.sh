#!/usr/bin/env bash
# The main job: build and package every FMU, FMI 2.0 and 3.0 (and the SSP files of the composed systems), print the
# paper's numbers as computed, draw Figures 6-8, and run the full composed demo (4 FMUs) through fmpy.
# Results go to out/.
#
#   bash examples/run.sh               the main job: the product's FMUs (Pendulum, DCMotor, Controller,
#                                      SampledController) for every platform, the Reference-FMU
#                                      re-makes (examples) and the containers' binary for this machine
#   bash examples/run.sh --everything  also the re-makes and the containers for every platform
#
# cargo's messages go to target/main-job/*.log (all of them shown if a build fails); what is shown
# is each build's progress (cargo fmu build -v shows cargo's messages as they come).
set -euo pipefail
cd "$(dirname "$0")/.."
everything=false
case "${1:-}" in
  --everything) everything=true ;;
  "") ;;
  *) echo "usage: bash examples/run.sh [--everything]" >&2; exit 2 ;;
esac
started=$SECONDS
times=()
# lap NAME: the time since the last lap, for the summary.
lap_at=$SECONDS
lap() { times+=("$(printf '%-44s %4d s' "$1" $((SECONDS - lap_at)))"); lap_at=$SECONDS; }
# phase K TEXT: where the main job is, for the person watching it (six phases).
phase() { echo; echo "== main job $1/6 ($((SECONDS - started)) s so far): $2"; }
phase 1 "setup: the venv's Python packages, the Rust targets, the linkers"
bash tests/setup-env.sh --main-job
lap "setup (tests/setup-env.sh --main-job)"
# Every host program the main job runs, and the runner's Python module, in one cargo invocation:
# cargo resolves features per invocation, so `cargo run -p A` then `cargo run -p B` (or maturin's
# own build of the module) would build the shared dependencies twice. The FMU crates' libraries
# are not: `cargo fmu build` builds them in a profile and cargo folders of its own (every target,
# linked by zig or MinGW; docs/platforms.md).
# (Setup and builds run one after the other: pip's install and maturin's build beside this build
# made the main job slower on 2 cores, 448-456 s against 383 s, as measured for issue 21.)
source tests/pyo3-env.sh
phase 2 "cargo build of cargo-fmu, the runner, its Python module, paper_numbers (messages: target/main-job/cargo-build.log)"
python3 tests/cargo-progress.py target/main-job/cargo-build.log \
  cargo build --release -p fmu-build --bin cargo-fmu -p holonomic --example paper_numbers \
  -p rustfmu-runner --bin rustfmu-runner -p rustfmu-runner-python --lib
bash tests/setup-env.sh --main-job --part module
lap "cargo build: cargo-fmu, paper_numbers, runner, module"
# The Reference-FMU re-makes are examples (`example = true` in their Cargo.toml): built for this
# machine only unless --everything (each of them for five platforms was 28 of the 55 fat-LTO links).
phase 3 "cargo fmu build: every FMU crate, FMI 2.0 and 3.0, packaged and validated; the SSP files"
if $everything; then
  target/release/cargo-fmu build --workspace --python .venv/bin/python
else
  target/release/cargo-fmu build --workspace --examples-on-host --python .venv/bin/python
fi
lap "FMUs and SSP files (cargo fmu build)"
# Each composed system as one FMU (cargo fmu container; the components inside, the runner's
# master in its binary, for every platform the components carry), beside the SSP files: FMI 2.0
# in target/fmu/containers, FMI 3.0 in target/fmu/containers/fmi3 (the same binary).
# The containers' binary (the runner's master) for this machine only unless --everything.
phase 4 "cargo fmu container: the composed systems as one FMU each"
mkdir -p target/fmu/containers
here=()
host=$(rustc -vV | sed -n 's/^host: //p')
[[ "$host" == *-linux-gnu ]] && host="$host.2.17"  # as the FMUs' Linux binaries: glibc 2.17 and newer
$everything || here=(--target "$host")
for s in PendulumLQR PendulumMotors fmi3/NetworkedPendulum; do
  target/release/cargo-fmu container "target/fmu/$s.ssp" -o "target/fmu/containers/${s#fmi3/}.fmu" --python .venv/bin/python "${here[@]}"
done
lap "container FMUs (cargo fmu container)"
phase 5 "the paper's numbers, Figures 6-8, the composed demo in fmpy, the clocked controller, the container"
mkdir -p out
target/release/examples/paper_numbers | tee out/paper_numbers.txt
.venv/bin/python examples/paper_figures.py --out out
lap "paper numbers, Figures 6-8"
.venv/bin/python examples/composed_demo.py --out out
# The FMI 3.0 clocked controller (its sample rate a clock) closing the loop, against the 2.0 one.
.venv/bin/python examples/clocked_controller.py --out out
# The closed loop as one FMU in fmpy, against the native runner on its SSP file.
.venv/bin/python examples/container_demo.py --out out
lap "composed demo (fmpy), clocked controller, container"
phase 6 "the native runner's command line, the Dask parameter studies"
# The full loop from the command line of the native SSP runner (runner/).
target/release/rustfmu-runner run target/fmu/PendulumMotors.ssp --stop-time 10 --step 1e-3 \
  --set pendulum.alpha1_0=0.2 --record pendulum.alpha1 --record pendulum.alpha2 --record motor1.tau \
  --record motor2.tau --output out/runner_motors.csv --no-progress
# Parameter studies on a Dask LocalCluster, small grids (the full ones: docs/parameter-studies.md),
# each closed loop run in-process by the native runner (the rustfmu_runner module).
rm -f out/study/roa.csv out/study/robust.csv
.venv/bin/python examples/parameter_study.py roa --out out/study --n 15 --no-progress --master native
.venv/bin/python examples/parameter_study.py robust --out out/study --samples 40 --no-progress --master native
lap "runner command line, Dask studies"

echo
echo "== Made"
echo "FMUs, FMI 2.0 (target/fmu): $(cd target/fmu && ls *.fmu | tr '\n' ' ')"
echo "FMUs, FMI 3.0 (target/fmu/fmi3): $(cd target/fmu/fmi3 && ls *.fmu | tr '\n' ' ')"
echo "SSP files (target/fmu; of the FMI 3.0 FMUs in target/fmu/fmi3): $(cd target/fmu && ls *.ssp 2>/dev/null | tr '\n' ' ')"
echo "SSP 2.0 files of systems of FMI 3.0 FMUs only (target/fmu/fmi3): $(cd target/fmu/fmi3 && for f in *.ssp; do [[ -e "$f" && ! -e "../$f" ]] && printf '%s ' "$f"; done)"
echo "Container FMUs, the SSP files' systems as one FMU each (target/fmu/containers, FMI 3.0 in containers/fmi3): $(cd target/fmu/containers && ls *.fmu | tr '\n' ' ')"
# The platforms each FMU carries: its binaries/ folders (the same for every FMU of one version).
platforms() { .venv/bin/python -c 'import sys, zipfile; print(" ".join(sorted({n.split("/")[1] for n in zipfile.ZipFile(sys.argv[1]).namelist() if n.startswith("binaries/") and n.count("/") > 1})))' "$1"; }
echo "Platforms: FMI 2.0 $(platforms target/fmu/Pendulum.fmu); FMI 3.0 $(platforms target/fmu/fmi3/Pendulum.fmu)"
echo "  (Linux binaries load on glibc >= 2.17; the macOS ones, for macOS >= 10.12 on Intel and >= 11.0 on Apple"
echo "  silicon, are built and checked here but never run: no Mac here. docs/platforms.md; cargo fmu info FILE.fmu)"
echo "Results (out/): the paper's numbers computed (paper_numbers.txt), Figures 6-8, the composed"
echo "demo (controller -> 2 motors -> pendulum through fmpy), the FMI 3.0 clocked controller's loop against"
echo "the 2.0 sampled one (clocked_controller.csv), the loop as one container FMU in fmpy against the runner"
echo "(container_demo.csv), the same loop in the native runner's"
echo "command line (runner_motors.csv), the Dask studies on the native runner (out/study):"
(cd out && find . -type f | sort | sed 's|^\./|  out/|')
echo "Time: $((SECONDS - started)) s in all"
for t in "${times[@]}"; do echo "  $t"; done
if ! $everything; then
  echo "Built for this machine only: the Reference-FMU re-makes (Dahlquist, BouncingBall, ...) and the"
  echo "containers' binary. For every platform, as the tests use them: bash examples/run.sh --everything"
fi
