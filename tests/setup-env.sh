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
#                                        runner's Python module (maturin), or the last two
#   bash tests/setup-env.sh [--main-job] --list
#                                        print the Debian packages that mode ensures, one a line,
#                                        installed or not, and exit (test_fresh_machine.py checks
#                                        them against the dependency trees of what the main job builds)
#
# Main job: the Rust targets x86_64-pc-windows-gnu and aarch64-unknown-linux-gnu (rustup) and their
# linkers (every FMU carries Linux and Windows binaries, the FMI 3.0 ones aarch64 Linux too);
# gcc and libclang-dev: the runner (its `fmi` importer crate) compiles fmi-sys, whose build script
# compiles C and runs bindgen; a venv at .venv with examples/requirements.txt and the runner's
# Python module (maturin). The tests add wine and qemu-user (they run the Windows and aarch64
# binaries), valgrind and binutils (the conformance suite's C host and symbol checks), libtbb12
# (ecospy) and tests/python/requirements.txt.
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
main_packages=(gcc-mingw-w64-x86-64:x86_64-w64-mingw32-gcc gcc-aarch64-linux-gnu:aarch64-linux-gnu-gcc
  gcc:gcc libclang-dev:)
test_packages=(wine:wine qemu-user:qemu-aarch64 valgrind:valgrind binutils:nm libtbb12:)
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
wants() { [ "$part" = both ] || [ "$part" = "$1" ] || { [ "$part" = python ] && [ "$1" != system ]; }; }
if wants system; then
for triple in x86_64-pc-windows-gnu aarch64-unknown-linux-gnu; do
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
  echo "setup-env: pip install -r $requirements"
  .venv/bin/pip install -q --disable-pip-version-check -r "$requirements"
  echo "$want" >"$stamp"
fi
step "venv and Python packages"
# ecospy's wheel ships its executables (ecos, proxyfmu) without the exec bit.
chmod +x .venv/lib/python3*/site-packages/ecospy/binaries/{ecos,proxyfmu} 2>/dev/null || true
fi

if wants module; then
# The native SSP runner's Python module (runner/python -> rustfmu_runner), built with maturin
# into .venv (release profile; maturin sets PYO3_BUILD_EXTENSION_MODULE, so that it does not link
# libpython); built again only when a source of it (or of a crate it uses) changed. In this
# workspace's target/, or RUSTFMU_MODULE_TARGET_DIR. It shares few compiled crates with the
# other builds: cargo resolves features for maturin's one package, and maturin's release units
# differ from `cargo build --release`'s even with the features aligned (56-133 s measured).
runner_sha=$(find runner tests/conformance/src -type f \( -name '*.rs' -o -name '*.toml' \) | sort | xargs cat Cargo.lock | sha256sum | cut -d' ' -f1)
if [ "$(cat .venv/.runner.sha 2>/dev/null)" != "$runner_sha" ] || ! .venv/bin/python -c "import rustfmu_runner" 2>/dev/null; then
  echo "setup-env: maturin develop --release (runner/python: the rustfmu_runner module)"
  module_target=$(realpath -m "${RUSTFMU_MODULE_TARGET_DIR:-target}")
  (cd runner/python && VIRTUAL_ENV="$PWD/../../.venv" CARGO_TARGET_DIR="$module_target" nice -n 10 ../../.venv/bin/maturin develop --release --quiet)
  echo "$runner_sha" >.venv/.runner.sha
fi
step "the runner's Python module (maturin)"
fi
echo "setup-env: ready ($((SECONDS - started)) s)"
