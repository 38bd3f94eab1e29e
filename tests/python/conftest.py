"""Shared fixtures: where the packaged FMUs are. tests/run.sh builds them before pytest runs."""

import hashlib
import os
import pathlib
import shutil
import subprocess
import tempfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU_DIR = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "fmu"


def packaged(relative: str, why: str) -> str:
    """Path of target/fmu/<relative>, a file `cargo run --release -p fmu-build` writes; fails with
    that command (and `why`, what to say after it) where it is missing."""
    path = FMU_DIR / relative
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo run --release -p fmu-build`{why}")
    return str(path)


def fmu(name: str) -> str:
    """Path of target/fmu/<name>.fmu; fails with the command that builds it."""
    return packaged(f"{name}.fmu", " first")


def fmu3(name: str) -> str:
    """Path of target/fmu/fmi3/<name>.fmu, the FMI 3.0 twin of fmu(name); fails with the command
    that builds it."""
    return packaged(f"fmi3/{name}.fmu", " first (it packages FMI 2.0 and 3.0)")


@pytest.fixture(scope="session")
def pendulum_fmu() -> str:
    return fmu("Pendulum")


# The target folder of every crate made by `cargo fmu new` in the tests (test_cargo_fmu,
# test_runner, test_windows): one, shared as CARGO_TARGET_DIR, so that their dependencies are
# built once (a user with several FMU crates does the same); kept, so that a second test run
# builds only what changed.
USER_TARGET = FMU_DIR.parent / "user-crates"


def outside_crate(name: str, fresh: bool = False) -> tuple[pathlib.Path, dict]:
    """A crate made by `cargo fmu new <name>` (this workspace's target/release/cargo-fmu) outside
    this workspace, as a user's crate is, built into USER_TARGET. `fresh`: made anew even if it
    exists (for tests that edit it). Returns the crate's folder and the environment that runs
    `cargo fmu` on it.

    The crate is outside the workspace (else cargo takes it for a member) and one per checkout: a
    crate kept from another checkout would build against that checkout's rustfmu (its path
    dependency)."""
    cargo_fmu = FMU_DIR.parent / "release" / "cargo-fmu"
    if not cargo_fmu.exists():
        pytest.fail(f"{cargo_fmu} is missing: build it with `cargo build --release -p fmu-build --bins`")
    checkout = hashlib.sha1(str(ROOT).encode()).hexdigest()[:12]
    where = pathlib.Path(tempfile.gettempdir()) / f"rustfmu-crates-{os.getuid()}-{checkout}"
    where.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env["PATH"] = f"{cargo_fmu.parent}{os.pathsep}{env['PATH']}"
    env["CARGO_TARGET_DIR"] = str(USER_TARGET)
    crate = where / name
    if fresh or not (crate / "Cargo.toml").exists():
        shutil.rmtree(crate, ignore_errors=True)
        out = subprocess.run(["cargo", "fmu", "new", name], cwd=where, env=env, capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, out.stderr
    return crate, env
