# Sourced by every script whose cargo build includes the runner's Python module
# (rustfmu-runner-python): pyo3 builds against the venv's interpreter, as an extension module
# (no libpython linked; pyo3 0.30 reads PYO3_BUILD_EXTENSION_MODULE where older releases had the
# `extension-module` feature). The same values in every build keep pyo3's build-script output, and
# so every unit, shared between the main job's build, the tests' build and `setup-env.sh --part module`.
PYO3_PYTHON="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/.venv/bin/python"
PYO3_BUILD_EXTENSION_MODULE=1
export PYO3_PYTHON PYO3_BUILD_EXTENSION_MODULE
