"""The aarch64 Linux binaries of the FMI 3.0 FMUs (binaries/aarch64-linux/<id>.so; FMI 2.0 names
no folder for aarch64), run where they will run: conformance/c/host3.c compiled with
Debian's aarch64-linux-gnu-gcc and run under qemu-user loads each one from the unzipped FMU,
makes 1,000 co-simulation steps and frees it; the x86-64 binary with the same inputs gives the
same trajectory to 1e-12. The FMI 3.0 container FMUs (target/fmu/containers/fmi3/, made by the main
job and tests/run.sh) as well: their aarch64 binary loads the components' aarch64 binaries from
its resources.

Needs gcc-aarch64-linux-gnu and qemu-user (tests/setup-env.sh installs them).
"""

import shutil
import time

import pytest

from conftest import FMU_DIR, ROOT
from test_windows import NAMES, STEPS, H, WORK, float_outputs, largest_difference, report, run, token, trace, unpack

SYSROOT = "/usr/aarch64-linux-gnu"


@pytest.fixture(scope="session")
def arm_host():
    for tool in ["gcc", "aarch64-linux-gnu-gcc", "qemu-aarch64"]:
        if not shutil.which(tool):
            pytest.fail(f"{tool} is missing: run `bash tests/setup-env.sh` (it installs gcc-aarch64-linux-gnu and qemu-user)")
    WORK.mkdir(parents=True, exist_ok=True)
    c = ROOT / "conformance" / "c" / "host3.c"
    out = run(["gcc", "-O2", "-Wall", "-Werror", "-o", WORK / "host3", c, "-ldl"])
    assert out.returncode == 0, out.stderr
    out = run(["aarch64-linux-gnu-gcc", "-O2", "-Wall", "-Werror", "-o", WORK / "host3-aarch64", c, "-ldl"])
    assert out.returncode == 0, out.stderr
    return WORK


def x86_64_and_aarch64(arm_host, fmu, name, sets):
    """Runs host3 on the FMU's x86_64-linux binary and, under qemu, on its aarch64-linux one;
    returns both trajectories and the seconds qemu took."""
    folder = arm_host / f"{fmu.parent.name}-{name}-3-aarch64"
    xml = unpack(fmu, folder)
    so = folder / "binaries" / "x86_64-linux" / f"{name}.so"
    arm = folder / "binaries" / "aarch64-linux" / f"{name}.so"
    assert so.exists() and arm.exists(), sorted(p.name for p in (folder / "binaries").iterdir())
    vrs = ",".join(str(v) for v in float_outputs(xml, True))
    args = [token(xml), f"{folder}/resources/", STEPS, H, -1, vrs, *sets]
    env = {"HOST_TRACE": "1", "PATH": "/usr/bin:/bin"}
    x86 = run([arm_host / "host3", so, *args], env=env)
    assert x86.returncode == 0, x86.stderr
    started = time.monotonic()
    a64 = run(["qemu-aarch64", "-L", SYSROOT, arm_host / "host3-aarch64", arm, *args], env=env)
    seconds = time.monotonic() - started
    assert a64.returncode == 0, a64.stderr
    a, b = trace(x86.stdout), trace(a64.stdout)
    assert len(a) == len(b) == STEPS, (len(a), len(b))
    return a, b, seconds


@pytest.mark.parametrize("name", NAMES)
def test_every_fmi3_fmu_runs_on_aarch64_as_on_x86_64(arm_host, name):
    fmu = FMU_DIR / "fmi3" / f"{name}.fmu"
    assert fmu.exists(), f"{fmu} is missing: run `cargo run --release -p fmu-build` first"
    a, b, seconds = x86_64_and_aarch64(arm_host, fmu, name, ["40=0.1"] if name == "Pendulum" else [])
    d = largest_difference(a, b)
    report(f"{name} FMI 3.0 on aarch64 (qemu), {STEPS} steps: largest |x86_64 - aarch64| = {d:.3g} (qemu run {seconds:.1f} s)")
    scale = max(1.0, max(abs(x) for row in a for x in row))
    assert d <= 1e-12 * scale, d
    if name == "Pendulum":
        assert a[-1] != a[0], "the pendulum did not move"


@pytest.mark.parametrize("name", ["PendulumLQR", "PendulumMotors"])
def test_the_fmi3_containers_run_on_aarch64_as_on_x86_64(arm_host, name):
    """Issue 49: the FMI 3.0 container carries binaries/aarch64-linux/, as every other FMI 3.0 FMU
    (cargo fmu container makes it of the components' FMI 3.0 FMUs, target/fmu/fmi3/<system>.ssp,
    which carry theirs; FMI 2.0 names no folder for aarch64); under qemu it loads the
    components' aarch64 binaries from its resources, and 1,000 steps equal the x86_64 ones'."""
    fmu = FMU_DIR / "containers" / "fmi3" / f"{name}.fmu"
    assert fmu.exists(), f"{fmu} is missing: run `bash tests/run.sh` (or the main job) first"
    a, b, seconds = x86_64_and_aarch64(arm_host, fmu, name, [])
    d = largest_difference(a, b)
    report(f"{name} container FMI 3.0 on aarch64 (qemu), {STEPS} steps: largest |x86_64 - aarch64| = {d:.3g} "
           f"(qemu run {seconds:.1f} s)")
    scale = max(1.0, max(abs(x) for row in a for x in row))
    assert d <= 1e-12 * scale, d
    assert a[-1] != a[0], "the loop did not move"
