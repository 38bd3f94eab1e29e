#!/usr/bin/env bash
# Installs what the main job or the tests need, on a fresh machine; safe to run again (it only
# installs what is missing).
#
#   bash tests/setup-env.sh              everything the tests need (tests/run.sh)
#   bash tests/setup-env.sh --main-job   what the main job's builds and scripts need (examples/run.sh;
#                                        --python-only is the old name)
#   bash tests/setup-env.sh [--main-job] --part system|packages|module|python
#                                        one part only: the Rust targets and Debian packages (what
#                                        the cargo builds need), the venv and its packages, the
#                                        runner's Python module (the cdylib of the last cargo build
#                                        copied into .venv; built if there is none), or the last two
#   bash tests/setup-env.sh [--main-job] --list
#                                        print the Debian packages that mode ensures, one a line,
#                                        installed or not, and exit (test_fresh_machine.py checks
#                                        them against the dependency trees of what the main job builds)
#
# Main job: the Rust targets x86_64-pc-windows-gnu, aarch64-unknown-linux-gnu, x86_64-apple-darwin and
# aarch64-apple-darwin (rustup) and their linkers (every FMU carries Linux, Windows and macOS
# binaries, the FMI 3.0 ones aarch64 Linux too; MinGW links Windows, zig from the venv's ziglang
# and cargo-zigbuild the others, Debian's aarch64 gcc is kept for the tests' qemu runs);
# gcc: the runner's FMU importer compiles its C logger (runner/c/logger.c, with the cc crate); a venv at .venv with examples/requirements.txt; after the caller's
# cargo build, the runner's Python module (--part module). The tests add wine and qemu-user (they run the Windows and aarch64
# binaries), valgrind and binutils (the conformance suite's C host and symbol checks), libtbb12
# (ecospy), libclang-dev (the benchmarks and one test import FMUs with the `fmi` crate, whose
# fmi-sys runs bindgen; the main job no longer builds it since the runner has its own importer)
# and tests/python/requirements.txt.
set -euo pipefail
cd "$(dirname "$0")/.."

main_job=false
list=false
part=both
while (($#)); do
  case "$1" in
    --main-job | --python-only) main_job=true ;;
    --list) list=true ;;
    --part)
      part=${2:-}
      shift
      [[ "$part" =~ ^(system|packages|module|python)$ ]] || {
        echo "setup-env: --part system, packages, module or python" >&2
        exit 2
      }
      ;;
    *) echo "setup-env: unknown argument '$1' (--main-job, --part system|packages|module|python, --list)" >&2; exit 2 ;;
  esac
  shift
done

# Debian packages: "package:command" (installed when the command is missing) or "package:"
# (installed when dpkg does not know it).
main_packages=(gcc-mingw-w64-x86-64:x86_64-w64-mingw32-gcc
  gcc:gcc)
test_packages=(gcc-aarch64-linux-gnu:aarch64-linux-gnu-gcc wine:wine qemu-user:qemu-aarch64 valgrind:valgrind binutils:nm libtbb12:
  libclang-dev:)
packages=("${main_packages[@]}")
$main_job || packages+=("${test_packages[@]}")

if $list; then
  for p in "${packages[@]}"; do echo "${p%%:*}"; done
  exit 0
fi

started=$SECONDS
# step NAME: prints how long the step since the last one took.
step_at=$SECONDS
step() { echo "setup-env: $1 ($((SECONDS - step_at)) s)"; step_at=$SECONDS; }
# wants PART: whether --part asks for PART.
# Without --part: the Rust targets, Debian packages and the venv; the module comes after the
# caller's cargo build (--part module), which compiles it.
wants() { { [ "$part" = both ] && [ "$1" != module ]; } || [ "$part" = "$1" ] || { [ "$part" = python ] && [ "$1" != system ]; }; }
if wants system; then
for triple in x86_64-pc-windows-gnu aarch64-unknown-linux-gnu x86_64-apple-darwin aarch64-apple-darwin; do
  if [ ! -d "$(rustc --print sysroot)/lib/rustlib/$triple/lib" ]; then
    echo "setup-env: rustup target add $triple"
    rustup target add "$triple"
  fi
done

need=()
for p in "${packages[@]}"; do
  name=${p%%:*}
  cmd=${p#*:}
  if [ -n "$cmd" ]; then
    command -v "$cmd" >/dev/null 2>&1 || need+=("$name")
  else
    dpkg -s "$name" >/dev/null 2>&1 || need+=("$name")
  fi
done
if ((${#need[@]})); then
  echo "setup-env: apt-get install ${need[*]}"
  sudo=""
  [ "$(id -u)" = 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${need[@]}" >/dev/null
fi
step "Rust targets and Debian packages"
fi

if wants packages; then
if [ ! -x .venv/bin/python ]; then
  echo "setup-env: creating .venv"
  python3 -m venv .venv
fi
# examples/requirements.txt for the main job; the tests' file includes it.
requirements=tests/python/requirements.txt
$main_job && requirements=examples/requirements.txt
stamp=.venv/.requirements.sha
want=$(cat "$requirements" examples/requirements.txt | sha256sum | cut -d' ' -f1)
have=$(cat "$stamp" 2>/dev/null || true)
# A venv made for the tests has the main job's packages too.
full=$(cat tests/python/requirements.txt examples/requirements.txt | sha256sum | cut -d' ' -f1)
if [ "$have" != "$want" ] && ! { $main_job && [ "$have" = "$full" ]; }; then
  # uv installs the same pinned wheels as pip in a few seconds (2.5 s against pip's 37-75 s for
  # the main job's file on a warm cache, measured for issue 21); pip only brings uv itself.
  echo "setup-env: uv pip install -r $requirements"
  [ -x .venv/bin/uv ] || .venv/bin/pip install -q --disable-pip-version-check uv==0.13.9
  .venv/bin/uv pip install -q --python .venv/bin/python -r "$requirements"
  echo "$want" >"$stamp"
fi
step "venv and Python packages"
# ecospy's wheel ships its executables (ecos, proxyfmu) without the exec bit.
chmod +x .venv/lib/python3*/site-packages/ecospy/binaries/{ecos,proxyfmu} 2>/dev/null || true
fi

if wants module; then
# The native SSP runner's Python module (runner/python -> rustfmu_runner), into .venv. The cdylib
# comes from the caller's one cargo build (examples/run.sh, tests/run.sh: `-p rustfmu-runner-python`
# beside everything else, with PYO3_PYTHON and PYO3_BUILD_EXTENSION_MODULE from
# tests/pyo3-env.sh), so that it shares every compiled crate of the runner's tree (the `fmi`
# importer with fmi-sys's bindgen, zip with its codecs, clap) with the runner's command line.
# `maturin develop --release` here built that tree a second time, in units of its own: 106-152 s
# of the main job's and CI's setup (issue 21). What maturin does besides the build, for a module
# of one extension and no Python files, is a copy under the interpreter's extension suffix; that
# copy is all this part does. `pip install ./runner/python` (maturin) still works for anyone else.
module_lib=target/release/librustfmu_runner.so
[ -n "${CARGO_TARGET_DIR:-}" ] && module_lib=$CARGO_TARGET_DIR/release/librustfmu_runner.so
if [ ! -f "$module_lib" ]; then
  # Run alone: build it, with the same environment as the main build (the units stay shared).
  echo "setup-env: cargo build --release -p rustfmu-runner-python (the rustfmu_runner module)"
  (source tests/pyo3-env.sh && cargo build --release -p rustfmu-runner-python --lib)
fi
site=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["platlib"])')
suffix=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_config_var("EXT_SUFFIX"))')
# A copy that maturin or pip installed before would shadow or duplicate this one.
rm -rf "$site"/rustfmu_runner "$site"/rustfmu_runner-*.dist-info "$site"/rustfmu_runner.pth "$site"/rustfmu_runner.*.so
cp "$module_lib" "$site/rustfmu_runner$suffix.tmp"
mv "$site/rustfmu_runner$suffix.tmp" "$site/rustfmu_runner$suffix"
.venv/bin/python -c 'import rustfmu_runner' || {
  echo "setup-env: the rustfmu_runner module built at $module_lib does not import in .venv" >&2
  exit 1
}
# isolate=True runs each component in a child process of the rustfmu-runner binary, which the
# module looks for in the environment's scripts folder (or $RUSTFMU_RUNNER, PATH).
runner_bin=$(dirname "$module_lib")/rustfmu-runner
if [ ! -f "$runner_bin" ]; then
  echo "setup-env: cargo build --release -p rustfmu-runner (the children of isolate=True)"
  (source tests/pyo3-env.sh && cargo build --release -p rustfmu-runner --bin rustfmu-runner)
fi
cp "$runner_bin" .venv/bin/rustfmu-runner.tmp
mv .venv/bin/rustfmu-runner.tmp .venv/bin/rustfmu-runner
step "the runner's Python module (copied from $module_lib) and .venv/bin/rustfmu-runner"
fi
echo "setup-env: ready ($((SECONDS - started)) s)"
