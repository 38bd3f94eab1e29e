#!/usr/bin/env bash
# Installs what the tests and examples need, on a fresh machine: Debian's libclang-dev (fmi-sys
# runs bindgen when the tests build) and valgrind, and a Python venv at .venv with
# tests/python/requirements.txt; and what the Windows binaries of the FMUs need: the Rust target
# x86_64-pc-windows-gnu (rustup target add), Debian's MinGW linker (gcc-mingw-w64-x86-64), and
# for the tests wine, which runs them; the same for aarch64 Linux (FMI 3.0): the target, Debian's
# gcc-aarch64-linux-gnu and, for the tests, qemu-user. `--python-only` (the main job) installs the venv and the
# cross-compilation pieces (target and linker), no libclang, valgrind or wine.
# Safe to run again: it only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

python_only=false
[ "${1:-}" = "--python-only" ] && python_only=true

need=()
# Cross compilation (every FMU of this project carries a linux64 and a win64 binary).
# (and aarch64 Linux in the FMI 3.0 FMUs).
for triple in x86_64-pc-windows-gnu aarch64-unknown-linux-gnu; do
  if [ ! -d "$(rustc --print sysroot)/lib/rustlib/$triple/lib" ]; then
    echo "setup-env: rustup target add $triple"
    rustup target add "$triple"
  fi
done
command -v x86_64-w64-mingw32-gcc >/dev/null 2>&1 || need+=(gcc-mingw-w64-x86-64)
command -v aarch64-linux-gnu-gcc >/dev/null 2>&1 || need+=(gcc-aarch64-linux-gnu)
if ! $python_only; then
command -v wine >/dev/null 2>&1 || need+=(wine)
command -v qemu-aarch64 >/dev/null 2>&1 || need+=(qemu-user)
command -v gcc >/dev/null 2>&1 || need+=(gcc)
dpkg -s libclang-dev >/dev/null 2>&1 || need+=(libclang-dev)
command -v valgrind >/dev/null 2>&1 || need+=(valgrind)
command -v nm >/dev/null 2>&1 || need+=(binutils)
# ecospy's libecosc.so (the Ecos SSP tests, tests/python/test_ssp_as_shipped.py) links libtbb.so.12.
dpkg -s libtbb12 >/dev/null 2>&1 || need+=(libtbb12)
fi
if ((${#need[@]})); then
  echo "setup-env: apt-get install ${need[*]}"
  sudo=""
  [ "$(id -u)" = 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${need[@]}" >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
  echo "setup-env: creating .venv"
  python3 -m venv .venv
fi
stamp=.venv/.requirements.sha
want=$(sha256sum tests/python/requirements.txt | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "setup-env: pip install -r tests/python/requirements.txt"
  .venv/bin/pip install -q --disable-pip-version-check -r tests/python/requirements.txt
  echo "$want" >"$stamp"
fi
# The native SSP runner's Python module (runner/python -> rustfmu_runner), built with maturin
# into .venv (pyo3's extension-module feature on, release profile, this workspace's target/);
# built again only when a source of it (or of a crate it uses) changed.
runner_sha=$(find runner tests/conformance/src -type f \( -name '*.rs' -o -name '*.toml' \) | sort | xargs cat Cargo.lock | sha256sum | cut -d' ' -f1)
if [ "$(cat .venv/.runner.sha 2>/dev/null)" != "$runner_sha" ] || ! .venv/bin/python -c "import rustfmu_runner" 2>/dev/null; then
  echo "setup-env: maturin develop --release (runner/python: the rustfmu_runner module)"
  (cd runner/python && VIRTUAL_ENV="$PWD/../../.venv" nice -n 10 ../../.venv/bin/maturin develop --release --quiet)
  echo "$runner_sha" >.venv/.runner.sha
fi
# ecospy's wheel ships its executables (ecos, proxyfmu) without the exec bit.
chmod +x .venv/lib/python3*/site-packages/ecospy/binaries/{ecos,proxyfmu} 2>/dev/null || true
