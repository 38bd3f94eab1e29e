#!/usr/bin/env bash
# Runs every test of the project on a fresh machine: installs what they need, checks format and
# lints, builds and packages every FMU (validated by fmu-build and by fmpy), runs the
# conformance suite on every FMU with `cargo fmu check`, the Rust tests, the Python tests that use
# the packaged FMUs as importers do, and the benchmarks in quick mode; ends with the pass/fail
# count of every suite.
set -euo pipefail
cd "$(dirname "$0")/.."

run_started=$SECONDS
bash tests/setup-env.sh
export PATH="$PWD/.venv/bin:$PATH"
# pyo3 (the runner's Python module) against the venv, as an extension module, in every cargo call.
source tests/pyo3-env.sh
# One seed for every random test of the run (the conformance suite's random call sequences, the
# FMU fuzzer); RUSTFMU_SEED=<it> bash tests/run.sh repeats them (issue 49).
export RUSTFMU_SEED="${RUSTFMU_SEED:-$(od -An -N8 -tu8 /dev/urandom | tr -d ' ')}"
echo "== random seed: RUSTFMU_SEED=$RUSTFMU_SEED (rerun with it to repeat the random tests)"
logs=$(mktemp -d)
summary=()
failed=0
total_pass=0
total_fail=0

# record NAME PASSED FAILED: with the seconds since the last record (the suite's time).
suite_started=$SECONDS
record() {
  summary+=("$(printf '%-34s %5d passed, %d failed %6d s' "$1" "$2" "$3" $((SECONDS - suite_started)))")
  suite_started=$SECONDS
  total_pass=$((total_pass + $2))
  total_fail=$((total_fail + $3))
  if [ "$3" -ne 0 ]; then failed=1; fi
}

# step NAME COMMAND...: a check that passes or fails as a whole.
step() {
  local name=$1
  shift
  echo "== $name"
  if "$@"; then record "$name" 1 0; else record "$name" 0 1; fi
}

echo "setup: $((SECONDS - run_started)) s"
suite_started=$SECONDS
step "cargo fmt --check" cargo fmt --all --check
# One cargo invocation over the whole workspace builds everything the later steps run
# (cargo-fmu, the runner, the benchmarks' binaries, every test binary). Cargo resolves features
# per invocation: `cargo run -p fmu-build` or `cargo test -p X` would build the shared
# dependencies again with other features (the whole dependency tree, minutes on 2 cores), so the
# steps below run the binaries built here and `cargo test --workspace` only runs what is built.
# `cargo build --tests` builds what `cargo test --no-run` builds (test binaries, the criterion
# bench in test mode, binaries, examples) and, in the same invocation, the libraries as such: the
# runner's Python module (a cdylib without tests) among them. A second `cargo build -p` for the
# module resolved other features and recompiled about 20 crates (50 s in CI).
# A step that fails is recorded and the run goes on (issue 53: every suite runs, the summary says
# what failed); what needs its result fails in turn and is recorded too.
rust_build() {
  cargo build --workspace --release --lib --bins --tests --examples && bash tests/setup-env.sh --part module
}
step "Rust build (cargo build --workspace)" rust_build
echo "== fmu-build: build, package, validate (fmpy too) every FMU and SSP file"
# The product FMU crates for each of its targets (Linux x86-64 and aarch64 on glibc 2.17, Windows x86-64, macOS Intel and
# Apple silicon; docs/platforms.md), FMI 2.0 and 3.0.
# target/release/cargo-fmu without `fmu` is `fmu-build`, the same as `cargo run --release -p fmu-build`.
# The examples (the Reference-FMU re-makes, the LS-BUS nodes) for every platform only where a test
# reads or runs their foreign binaries: test_platforms.py's FMUS (the product crates are built for
# every platform anyway); the others (Clocks, StateSpace, the six LS-BUS FMUs) for this machine,
# as the main job builds them: 32 fat-LTO links of binaries no test looks at (issue 53). A test
# that starts reading another example's foreign binary fails on its missing folder: add it here.
# `bash examples/run.sh --everything` builds every crate for every platform.
everywhere=bouncing-ball-fmu,dahlquist-fmu,feedthrough-fmu,stair-fmu,van-der-pol-fmu
fmu_build_status=0
target/release/cargo-fmu build --workspace --examples-on-host --examples-everywhere "$everywhere" \
  --python .venv/bin/python || fmu_build_status=$?
# FMI 2.0 in target/fmu/, FMI 3.0 (the same binaries, with the 3.0 description) in target/fmu/fmi3/.
shopt -s nullglob
fmus=(target/fmu/*.fmu target/fmu/fmi3/*.fmu)
shopt -u nullglob
if [ "$fmu_build_status" -eq 0 ]; then
  record "fmu-build (package + validate)" "${#fmus[@]}" 0
else
  record "fmu-build (package + validate; exit $fmu_build_status)" 0 1
fi
# The FMU build (`cargo build -p <FMU crates>`) must have reused the test build's units: if the two
# selections resolve other dependency features, cargo compiles the FMU crates' tree twice and the
# Rust tests below recompile the FMU crates and relink every test binary that links them (190 s in
# CI before workspace-hack/). Nothing may compile here; if something does, its features go into
# workspace-hack/Cargo.toml (compare `cargo tree -e features` of both selections).
reuses_test_build() {
  local out
  out=$(cargo test --workspace --release --no-run 2>&1) || { echo "$out"; return 1; }
  if echo "$out" | grep -E '^ *Compiling '; then
    echo "the FMU build changed units of the test build (above): see workspace-hack/Cargo.toml"
    return 1
  fi
}
step "FMU build reused the test build" reuses_test_build
# The composed systems as container FMUs (issue 28), for every platform their components carry:
# tests/python/test_container.py, test_container_fmi3.py and test_windows.py run them (FMI 2.0
# and FMI 3.0, containers/fmi3/).
containers() {
  for s in PendulumLQR PendulumMotors fmi3/NetworkedPendulum; do
    target/release/cargo-fmu fmu container "target/fmu/$s.ssp" -o "target/fmu/containers/${s#fmi3/}.fmu" \
      --python .venv/bin/python || return 1
  done
}
mkdir -p target/fmu/containers
step "cargo fmu container (PendulumLQR, PendulumMotors, NetworkedPendulum)" containers
# The build refreshes modelDescription/ from the built libraries: a committed file it changed was stale.
step "modelDescription/ is up to date" git diff --exit-code --stat -- modelDescription
n=0
echo "== fmutool -check (fmu-manipulation-toolbox) on every FMU, FMI 2.0 and 3.0"
# fmu-manipulation-toolbox 2.0 checks FMI 3.0 descriptions too (its XSD and rules for 2.0 and 3.0).
for fmu in "${fmus[@]}"; do fmutool -input "$fmu" -check && n=$((n + 1)) || record "fmutool -check $fmu" 0 1; done
record "fmutool -check" "$n" 0

# The conformance suite's fmu-check cross-compiled for Windows, for test_windows.py (it runs inside
# the Python tests now, issue 53): built here, beside the checks below, which use one core each,
# and handed to the test in RUSTFMU_FMU_CHECK_EXE. Built by the test's fixture, it waited for the
# cargo lock that clippy holds beside the Python tests (about 450 s).
(
  nice -n 10 cargo build --release --target x86_64-pc-windows-gnu -p fmi-conformance --bin fmu-check \
    >"$logs/fmu-check-exe.log" 2>&1
  echo $? >"$logs/fmu-check-exe.rc"
) &
fmu_check_exe_build=$!

echo "== independent importers (../shared/independent/: fmusim, fmusim-rs, fmuCheck) on every FMU, beside cargo fmu check"
# tests/independent/README.md: validation, every interface, fmuCheck's step sizes, results against
# fmpy and beside the C Reference-FMUs; one record per tool and FMU. It runs one simulation at a
# time, as the conformance suite below runs one check at a time: side by side they use both cores
# (issue 53; alone they took about 360 s and 300 s of CI). Its output is printed after the suite's.
independent_started=$SECONDS
(
  st=0
  python tests/independent/run.py --records "$logs/independent.tsv" >"$logs/independent.log" 2>&1 || st=$?
  echo "$st" >"$logs/independent.rc"
  echo $((SECONDS - independent_started)) >"$logs/independent.seconds"
) &
independent=$!

echo "== cargo fmu check --strict (black-box conformance suite) on every FMU, FMI 2.0 and 3.0"
# --strict: a warning (what the standard leaves to the FMU, such as refusing NaN) is a failure.
for fmu in "${fmus[@]}"; do
  name=${fmu#target/fmu/}
  out="$logs/check-${name//\//-}.log"
  target/release/cargo-fmu fmu check --strict "$fmu" | tee "$out" || true
  line=$( (grep -E '^[0-9]+ passed, [0-9]+ failed' "$out" || true) | tail -n 1)
  p=$(echo "$line" | sed -E 's/^([0-9]+) passed.*/\1/')
  f=$(echo "$line" | sed -E 's/^[0-9]+ passed, ([0-9]+) failed.*/\1/')
  [ -n "$line" ] || { p=0; f=1; }
  record "cargo fmu check $name" "$p" "$f"
done

wait "$independent"
echo "== independent importers (ran beside cargo fmu check: $(cat "$logs/independent.seconds") s)"
cat "$logs/independent.log"
st=$(cat "$logs/independent.rc")
nf=0
while IFS=$'\t' read -r name p f; do record "$name" "$p" "$f"; nf=$((nf + f)); done < <(cat "$logs/independent.tsv" 2>/dev/null)
[ "$st" -eq 0 ] || [ "$nf" -ne 0 ] || record "independent importers (exit $st)" 0 1


wait "$fmu_check_exe_build" || true
if [ "$(cat "$logs/fmu-check-exe.rc")" = 0 ]; then
  export RUSTFMU_FMU_CHECK_EXE="$PWD/target/x86_64-pc-windows-gnu/release/fmu-check.exe"
else
  echo "fmu-check.exe did not build (test_windows.py's fixture tries again and fails with cargo's message):"
  tail -n 30 "$logs/fmu-check-exe.log"
fi

echo "== Rust tests (cargo test --workspace --no-fail-fast)"
# --no-fail-fast: a failing test binary does not stop the ones after it (without it one failure
# hid some 300 tests, issue 53). A binary that starts but prints no "test result:" line (it
# crashed or was killed) counts as one failure, and the summary says how many did not finish.
set +e
cargo test --workspace --release --no-fail-fast 2>&1 | tee "$logs/cargo-test.log"
rust_status=${PIPESTATUS[0]}
set -e
p=$( (grep -E '^test result:' "$logs/cargo-test.log" || true) | sed -E 's/.* ([0-9]+) passed.*/\1/' | awk '{s+=$1} END {print s+0}')
f=$( (grep -E '^test result:' "$logs/cargo-test.log" || true) | sed -E 's/.* ([0-9]+) failed.*/\1/' | awk '{s+=$1} END {print s+0}')
# (the criterion bench in test mode prints no "test result:" line: not counted; it fails by status)
binaries=$( (grep -E '^ +(Running|Doc-tests) ' "$logs/cargo-test.log" || true) | grep -cv 'Running benches/' || true)
reported=$(grep -cE '^test result:' "$logs/cargo-test.log" || true)
unfinished=$((binaries - reported))
if [ "$unfinished" -gt 0 ]; then f=$((f + unfinished)); fi
[ "$rust_status" -eq 0 ] || f=$((f > 0 ? f : 1))
record "Rust tests ($binaries binaries, $unfinished unfinished)" "${p:-0}" "${f:-1}"

# Issue 51: cargo fmu check (default verdicts) on each Reference FMU of ../shared/independent/,
# another exporter's FMUs, as a vendor runs the checker: each run must reach its end with a report
# (its failed verdicts are the Reference FMUs' own defects, each naming the standard's section) and
# a JUnit file that parses; 100 random sequences per FMU keep it short. It runs beside the Python
# tests (after clippy; about 5 minutes of one core) and writes its lines and counts to $logs/ref*.
reference_checks() {
  local ref_dir=../shared/independent/reference-fmus n=0 nf=0 fmu v out
  for fmu in "$ref_dir"/2.0/*.fmu "$ref_dir"/3.0/*.fmu; do
    [ -e "$fmu" ] || continue
    v=$(basename "$(dirname "$fmu")")
    out="$logs/ref-check-$v-$(basename "$fmu" .fmu)"
    target/release/cargo-fmu fmu check "$fmu" --random-sequences 100 --junit "$out.xml" >"$out.log" 2>&1 || true
    if grep -qE '^[0-9]+ passed, [0-9]+ failed, [0-9]+ warned, [0-9]+ skipped$' "$out.log" &&
      python -c 'import sys, xml.etree.ElementTree as E; E.parse(sys.argv[1])' "$out.xml"; then
      n=$((n + 1))
      echo "$v/$(basename "$fmu"): $(tail -n 1 "$out.log")"
    else
      nf=$((nf + 1))
      echo "$v/$(basename "$fmu"): no report"
      tail -n 20 "$out.log"
    fi
  done
  echo "$n $nf" >"$logs/ref.counts"
}

# Clippy, cargo doc and the Reference-FMU checks run beside the Python tests: those run one
# simulation at a time per worker, and these are a build that uses both cores and runs on one.
# Their output goes to logs, printed after the Python tests. (The wine and qemu tests ran here
# too, after them, and ended about 385 s after the Python tests in session 11's CI: they are in
# the Python tests' own run now, issue 53.)
(
  set +e
  started=$SECONDS
  cargo clippy --workspace --all-targets --release -- -D warnings >"$logs/clippy.log" 2>&1
  echo $? >"$logs/clippy.rc"
  echo $((SECONDS - started)) >"$logs/clippy.seconds"
  # The runtime's and the derive's documentation builds without a warning (broken links, bad
  # examples' markup): what a model author reads. Reuses clippy's check build of the dependencies.
  RUSTDOCFLAGS="-D warnings" cargo doc --release --no-deps -p rustfmu -p rustfmu-derive >"$logs/doc.log" 2>&1
  echo $? >"$logs/doc.rc"
  started=$SECONDS
  reference_checks >"$logs/ref.log" 2>&1
  echo $((SECONDS - started)) >"$logs/ref.seconds"
) &
beside=$!

echo "== Python tests (two workers, one test file each at a time), the wine and qemu tests among them"
# Two pytest-xdist workers, each taking whole files (--dist loadfile: a file's module and session
# fixtures, its `cargo fmu new` crates and its tmp folders stay in one process): most tests run one
# simulation on one core, so one worker left the second core to the builds and runs beside it,
# which need less than the Python suite's 1729 s (session 10; issue 53). The JUnit file gives the
# wine/qemu files' counts apart (their own line in the summary, as when they ran alone).
set +e
rm -f target/wine-test/report.txt
python -m pytest tests/python -q -p no:cacheprovider -n 2 --dist loadfile --durations=25 \
  --junitxml="$logs/pytest.xml" 2>&1 | tee "$logs/pytest.log"
py_status=${PIPESTATUS[0]}
set -e
# "all|platforms passed failed": every test of the run, and those of test_windows.py and
# test_aarch64.py; a file that could not be read counts as one failure.
counts=$(python - "$logs/pytest.xml" <<'PY' || echo "0 1 0 1"
import sys, xml.etree.ElementTree as E
n = {"all": [0, 0], "platforms": [0, 0]}
for case in E.parse(sys.argv[1]).iter("testcase"):
    kinds = {child.tag for child in case}
    if "skipped" in kinds:
        continue
    failed = bool(kinds & {"failure", "error"})
    groups = ["all"] + (["platforms"] if case.get("classname", "").split(".")[-1] in ("test_windows", "test_aarch64") else [])
    for g in groups:
        n[g][failed] += 1
print(*n["all"], *n["platforms"])
PY
)
read -r p f wp wf <<<"$counts"
cat target/wine-test/report.txt 2>/dev/null || true
[ "$py_status" -eq 0 ] || f=$(( ${f:-0} > 0 ? f : 1 ))
record "Python tests (all but wine/qemu)" "$((p - wp))" "$((f - wf))"
suite_started=$SECONDS
record "Windows (wine), aarch64 (qemu) in it" "$wp" "$wf"

wait "$beside"
echo "== cargo clippy -D warnings (ran beside the Python tests)"
cat "$logs/clippy.log"
suite_started=$((SECONDS - $(cat "$logs/clippy.seconds")))
if [ "$(cat "$logs/clippy.rc")" = 0 ]; then record "cargo clippy -D warnings" 1 0; else record "cargo clippy -D warnings" 0 1; fi
echo "== cargo doc (RUSTDOCFLAGS=-D warnings) of rustfmu and rustfmu-derive"
cat "$logs/doc.log"
if [ "$(cat "$logs/doc.rc")" = 0 ]; then record "cargo doc -D warnings" 1 0; else record "cargo doc -D warnings" 0 1; fi

echo "== cargo fmu check (default verdicts) on each Reference FMU (ran beside the Python tests: $(cat "$logs/ref.seconds" 2>/dev/null) s)"
cat "$logs/ref.log"
read -r n nf < <(cat "$logs/ref.counts" 2>/dev/null || echo "0 1")
suite_started=$((SECONDS - $(cat "$logs/ref.seconds" 2>/dev/null || echo 0)))
record "cargo fmu check Reference FMUs" "$n" "$nf"

step "benchmarks still run (quick mode)" bash bench/quick.sh

echo
echo "== Summary"
for s in "${summary[@]}"; do echo "$s"; done
echo "random seed: RUSTFMU_SEED=$RUSTFMU_SEED"
echo "time: $((SECONDS - run_started)) s in all (the setup included)"
echo "total: $total_pass passed, $total_fail failed"
exit "$failed"
