"""Shared fixtures: where the packaged FMUs are. tests/run.sh builds them before pytest runs."""

import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU_DIR = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "fmu"


def fmu(name: str) -> str:
    """Path of target/fmu/<name>.fmu; fails with the command that builds it."""
    path = FMU_DIR / f"{name}.fmu"
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo run --release -p fmu-build` first")
    return str(path)


def fmu3(name: str) -> str:
    """Path of target/fmu/fmi3/<name>.fmu, the FMI 3.0 twin of fmu(name); fails with the command
    that builds it."""
    path = FMU_DIR / "fmi3" / f"{name}.fmu"
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo run --release -p fmu-build` first (it packages FMI 2.0 and 3.0)")
    return str(path)


@pytest.fixture(scope="session")
def pendulum_fmu() -> str:
    return fmu("Pendulum")
