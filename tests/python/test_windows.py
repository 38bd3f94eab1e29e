"""The Windows binaries of the packaged FMUs, run where they will run: the project's C hosts
(conformance/c/host.c for FMI 2.0, host3.c for FMI 3.0) compiled for Windows with MinGW
and run under wine load binaries/win64/<id>.dll (3.0: binaries/x86_64-windows/) from the unzipped
FMU, make 1,000 co-simulation steps and free; the same hosts compiled for Linux run the linux64
binary with the same inputs, and the two trajectories must agree to 1e-12.

Needs wine and gcc-mingw-w64-x86-64 (tests/setup-env.sh installs them). The wine prefix is kept
in target/wine-prefix (its first start takes ~15 s, later ones ~1 s). The largest differences and
the times go to target/wine-test/report.txt.
"""

import os
import pathlib
import re
import shutil
import struct
import subprocess
import time
import zipfile

import pytest

from conftest import FMU_DIR, ROOT, USER_TARGET, outside_crate

NAMES = ["Pendulum", "Controller", "DCMotor"]
STEPS = 1000
H = 0.001
WORK = FMU_DIR.parent / "wine-test"
PREFIX = FMU_DIR.parent / "wine-prefix"
NICE = ["nice", "-n", "19"]


def run(cmd, **kw):
    return subprocess.run(NICE + [str(c) for c in cmd], capture_output=True, text=True, timeout=600, **kw)


@pytest.fixture(scope="session")
def hosts():
    """host, host3 (Linux) and host.exe, host3.exe, bcryptprimitives.dll (Windows) in WORK."""
    for tool in ["gcc", "x86_64-w64-mingw32-gcc", "wine"]:
        if not shutil.which(tool):
            pytest.fail(f"{tool} is missing: run `bash tests/setup-env.sh` (it installs gcc-mingw-w64-x86-64 and wine)")
    WORK.mkdir(parents=True, exist_ok=True)
    c = ROOT / "conformance" / "c"
    started = time.monotonic()
    for name in ["host", "host3"]:
        out = run(["gcc", "-O2", "-Wall", "-Werror", "-o", WORK / name, c / f"{name}.c", "-ldl"])
        assert out.returncode == 0, out.stderr
        out = run(["x86_64-w64-mingw32-gcc", "-O2", "-Wall", "-Werror", "-o", WORK / f"{name}.exe", c / f"{name}.c"])
        assert out.returncode == 0, out.stderr
    # Wine 8 lacks bcryptprimitives.dll (Windows 10 and later have it): a stand-in next to the
    # .exe, for the test hosts only (tests/wine/bcryptprimitives.c).
    out = run(
        [
            "x86_64-w64-mingw32-gcc",
            "-O2",
            "-Wall",
            "-shared",
            "-o",
            WORK / "bcryptprimitives.dll",
            ROOT / "tests" / "wine" / "bcryptprimitives.c",
            "-ladvapi32",
        ]
    )
    assert out.returncode == 0, out.stderr
    report(f"C hosts compiled (gcc and MinGW): {time.monotonic() - started:.1f} s")
    return WORK


def report(line: str):
    WORK.mkdir(parents=True, exist_ok=True)
    with open(WORK / "report.txt", "a") as f:
        f.write(line + "\n")


def wine_env():
    env = dict(os.environ)
    env.update(WINEPREFIX=str(PREFIX), WINEDEBUG="-all", HOST_TRACE="1")
    return env


def unpack(fmu: pathlib.Path, into: pathlib.Path) -> str:
    if into.exists():
        shutil.rmtree(into)
    with zipfile.ZipFile(fmu) as z:
        z.extractall(into)
    return (into / "modelDescription.xml").read_text()


def token(xml: str) -> str:
    return re.search(r'(?:guid|instantiationToken)="([^"]*)"', xml).group(1)


def float_outputs(xml: str, fmi3: bool) -> list[int]:
    if fmi3:
        found = re.findall(r"<Float64 ([^>]*)>", xml) + re.findall(r"<Float64 ([^>]*)/>", xml)
    else:
        found = [
            attrs
            for attrs, body in re.findall(r"<ScalarVariable ([^>]*)>(.*?)</ScalarVariable>", xml, re.S)
            if "<Real" in body
        ]
    vrs = []
    for attrs in found:
        if 'causality="output"' in attrs:
            vrs.append(int(re.search(r'valueReference="(\d+)"', attrs).group(1)))
    return sorted(set(vrs))


def trace(stdout: str) -> list[list[float]]:
    rows = []
    for line in stdout.splitlines():
        if line.startswith("trace "):
            bits = line.split()[2:]
            rows.append([struct.unpack("<d", struct.pack("<Q", int(b, 16)))[0] for b in bits])
    return rows


def linux_and_windows(hosts: pathlib.Path, name: str, fmi3: bool, sets: list[str], fmu: pathlib.Path | None = None):
    """Runs the Linux host on the .so and the Windows host under wine on the .dll of an FMU
    (default: this project's target/fmu/[fmi3/]<name>.fmu); returns both trajectories and the
    seconds wine took."""
    fmu = fmu or FMU_DIR / ("fmi3" if fmi3 else "") / f"{name}.fmu"
    assert fmu.exists(), f"{fmu} is missing: run `cargo run --release -p fmu-build` first"
    folder = hosts / f"{name}-{'3' if fmi3 else '2'}"
    xml = unpack(fmu, folder)
    so = folder / "binaries" / ("x86_64-linux" if fmi3 else "linux64") / f"{name}.so"
    dll = folder / "binaries" / ("x86_64-windows" if fmi3 else "win64") / f"{name}.dll"
    assert so.exists() and dll.exists(), sorted(p.name for p in (folder / "binaries").iterdir())
    vrs = ",".join(str(v) for v in float_outputs(xml, fmi3))
    assert vrs, "no Float64 output"
    host = "host3" if fmi3 else "host"
    # FMI 2.0: a file URI of resources/; FMI 3.0: a native path with a trailing separator.
    res_linux = f"{folder}/resources/" if fmi3 else f"file://{folder}/resources"
    res_windows = f"Z:{folder}/resources/".replace("/", "\\") if fmi3 else f"file:///Z:{folder}/resources"
    extra = ["-1"] if fmi3 else []
    lin = run([hosts / host, so, token(xml), res_linux, STEPS, H, *extra, vrs, *sets], env=wine_env())
    assert lin.returncode == 0, lin.stderr
    started = time.monotonic()
    dll_arg = "Z:" + str(dll).replace("/", "\\")
    win = run(
        ["wine", hosts / f"{host}.exe", dll_arg, token(xml), res_windows, STEPS, H, *extra, vrs, *sets],
        env=wine_env(),
        cwd=hosts,
    )
    seconds = time.monotonic() - started
    assert win.returncode == 0, f"wine {host}.exe {name}: {win.stdout[-2000:]} {win.stderr[-2000:]}"
    a, b = trace(lin.stdout), trace(win.stdout)
    assert len(a) == len(b) == STEPS, (len(a), len(b))
    return a, b, seconds


def largest_difference(a, b) -> float:
    return max(abs(x - y) for ra, rb in zip(a, b) for x, y in zip(ra, rb))


@pytest.mark.parametrize("fmi3", [False, True], ids=["fmi2", "fmi3"])
def test_the_pendulum_from_alpha1_0_1_gives_the_linux_trajectory_on_windows(hosts, fmi3):
    # alpha1_0 (vr 40) = 0.1: the pendulum falls; 1,000 steps of 1 ms.
    a, b, seconds = linux_and_windows(hosts, "Pendulum", fmi3, ["40=0.1"])
    d = largest_difference(a, b)
    report(
        f"Pendulum FMI {'3.0' if fmi3 else '2.0'} from alpha1 = 0.1, {STEPS} steps: largest |linux - windows| = {d:.3g} "
        f"(wine run {seconds:.1f} s)"
    )
    assert d <= 1e-12, d
    assert a[-1] != a[0], "the pendulum did not move"


@pytest.mark.parametrize("fmi3", [False, True], ids=["fmi2", "fmi3"])
@pytest.mark.parametrize("name", NAMES[1:])
def test_every_fmu_runs_on_windows_as_on_linux(hosts, name, fmi3):
    a, b, seconds = linux_and_windows(hosts, name, fmi3, [])
    d = largest_difference(a, b)
    scale = max(1.0, max(abs(x) for row in a for x in row))
    report(f"{name} FMI {'3.0' if fmi3 else '2.0'}, {STEPS} steps: largest |linux - windows| = {d:.3g} (wine run {seconds:.1f} s)")
    assert d <= 1e-12 * scale, d


# -- A crate of a user's, outside this workspace, asking for Linux and Windows in its Cargo.toml --

TARGETS = '["x86_64-unknown-linux-gnu", "x86_64-pc-windows-gnu"]'


@pytest.fixture(scope="session")
def user_crate_fmus():
    """WinLag.fmu (FMI 2.0 and 3.0) of a crate made by `cargo fmu new win-lag` outside this
    workspace, whose `[package.metadata.fmu]` names the Linux and the Windows target; built with
    plain `cargo fmu build` into the tests' shared target folder of such crates (kept: a second
    run builds nothing)."""
    crate, env = outside_crate("win-lag")
    manifest = crate / "Cargo.toml"
    text = manifest.read_text()
    if not re.search(r"^targets =", text, re.M):
        assert "[package.metadata.fmu]\n" in text, text
        text = text.replace("[package.metadata.fmu]\n", f"[package.metadata.fmu]\ntargets = {TARGETS}\n")
        manifest.write_text(text)
    started = time.monotonic()
    out = subprocess.run(NICE + ["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=1800)
    assert out.returncode == 0, out.stderr[-5000:]
    report(f"cargo fmu build of a `cargo fmu new` crate for Linux and Windows, FMI 2.0 and 3.0: {time.monotonic() - started:.1f} s")
    fmus = USER_TARGET / "fmu"
    return {False: fmus / "WinLag.fmu", True: fmus / "fmi3" / "WinLag.fmu"}


@pytest.mark.parametrize("fmi3", [False, True], ids=["fmi2", "fmi3"])
def test_a_users_crate_gets_the_windows_binary_its_cargo_toml_asks_for(hosts, user_crate_fmus, fmi3):
    fmu = user_crate_fmus[fmi3]
    with zipfile.ZipFile(fmu) as z:
        names = set(z.namelist())
    folders = ("x86_64-linux", "x86_64-windows") if fmi3 else ("linux64", "win64")
    assert {f"binaries/{folders[0]}/WinLag.so", f"binaries/{folders[1]}/WinLag.dll"} <= names, sorted(names)
    import fmpy.validation

    assert fmpy.validation.validate_fmu(str(fmu)) == []
    # u (vr 0) = 1 from rest: y = 1 - e^(-t/T), T = 0.1 s.
    a, b, seconds = linux_and_windows(hosts, "WinLag", fmi3, ["0=1.0"], fmu=fmu)
    d = largest_difference(a, b)
    report(f"WinLag (cargo fmu new) FMI {'3.0' if fmi3 else '2.0'}, {STEPS} steps: largest |linux - windows| = {d:.3g} (wine run {seconds:.1f} s)")
    assert d <= 1e-12, d
    import math

    for k in [0, 99, STEPS - 1]:
        t = (k + 1) * H
        assert abs(b[k][0] - (1.0 - math.exp(-t / 0.1))) <= 1e-9, (k, b[k])


# The conformance suite's black-box checks on the Windows binaries: the suite's fmu-check
# cross-compiled for Windows and run under wine picks binaries/win64/<id>.dll (3.0:
# binaries/x86_64-windows/). Every check runs except the group "native C host/valgrind", which
# needs cc, nm, readelf and valgrind (Linux tools: those checks skip themselves, saying so);
# the Windows C host is test_every_fmu_runs_on_windows_as_on_linux above, the PE tables
# fmu-build/tests/packages/windows_binaries.rs.
RANDOM_SEQUENCES = 200
NATIVE = "native C host/valgrind"


@pytest.fixture(scope="session")
def fmu_check_exe(hosts):
    # tests/run.sh builds it before the Python tests (beside the conformance checks) and says where:
    # a cargo build here would wait for the lock of the clippy run beside the Python tests.
    built = os.environ.get("RUSTFMU_FMU_CHECK_EXE")
    if built:
        shutil.copy(built, hosts / "fmu-check.exe")
        report(f"fmu-check.exe for x86_64-pc-windows-gnu: built by tests/run.sh ({built})")
        return hosts / "fmu-check.exe"
    started = time.monotonic()
    out = run(
        ["cargo", "build", "--release", "--target", "x86_64-pc-windows-gnu", "-p", "fmi-conformance", "--bin", "fmu-check"],
        cwd=ROOT,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    exe = FMU_DIR.parent / "x86_64-pc-windows-gnu" / "release" / "fmu-check.exe"
    shutil.copy(exe, hosts / "fmu-check.exe")
    report(f"fmu-check cross-compiled for x86_64-pc-windows-gnu: {time.monotonic() - started:.1f} s")
    return hosts / "fmu-check.exe"


# Found by this suite's "instances on threads" check: under wine a Controller run on a thread
# of its own differed in the last bits from the main thread's (LQR gains a few ulps apart).
# msvcrt's pow, exp and expm1 depend on the calling thread's x87 precision control, which wine
# sets to 0x37f on the main thread and 0x27f on new ones (measured: 2,877 of 20,000 pow and
# 3,437 of 20,000 exp results differ between the two; sin, cos, log, hypot, sqrt none). The
# models and the integrator take exp, expm1 and pow from the `libm` crate now, and this check
# passes for every FMU. (nalgebra's matrix exponential in the DC motor still calls msvcrt's pow
# to choose its Padé degree; a last bit there changes the result only at a choice boundary.)
CONFORMANCE_CASES = [
    pytest.param(name, fmi3, id=f"{name}-{'fmi3' if fmi3 else 'fmi2'}")
    for name in NAMES
    for fmi3 in [False, True]
]


@pytest.fixture(scope="session")
def conformance_under_wine(fmu_check_exe):
    """fmu-check.exe under wine on every FMU of CONFORMANCE_CASES, two at a time: a run is one
    wine process on one core most of its time, and CI has two (this saved about 50 s of CI).
    {(name, fmi3): (completed process, seconds)}."""
    from concurrent.futures import ThreadPoolExecutor

    def one(case):
        name, fmi3 = case
        fmu = FMU_DIR / ("fmi3" if fmi3 else "") / f"{name}.fmu"
        started = time.monotonic()
        # A check's time-out well above the default 30 s: under wine, two at a time on a loaded
        # machine, the FMI 3.0 memory check (42,000 instantiations, each with a file-system
        # call that wine makes slow) takes 20-45 s.
        out = run(
            ["wine", fmu_check_exe, "Z:" + str(fmu).replace("/", "\\"), "--random-sequences", RANDOM_SEQUENCES,
             "--timeout", "300", "--strict"],
            env=wine_env(),
            cwd=fmu_check_exe.parent,
        )
        return case, (out, time.monotonic() - started)

    cases = [(name, fmi3) for name in NAMES for fmi3 in [False, True]]
    with ThreadPoolExecutor(max_workers=2) as pool:
        return dict(pool.map(one, cases))


@pytest.mark.parametrize("name,fmi3", CONFORMANCE_CASES)
def test_the_conformance_suite_passes_on_the_windows_binaries_under_wine(conformance_under_wine, name, fmi3):
    out, seconds = conformance_under_wine[(name, fmi3)]
    summary = [l for l in out.stdout.splitlines() if re.match(r"^\d+ passed, \d+ failed", l)]
    assert summary, out.stdout[-3000:] + out.stderr[-3000:]
    counts = {word: int(n) for n, word in re.findall(r"(\d+) (passed|failed|warned|skipped)", summary[-1])}
    passed, failed = counts["passed"], counts["failed"]
    report(f"fmu-check.exe under wine, {name} FMI {'3.0' if fmi3 else '2.0'}: {summary[-1]} ({seconds:.1f} s)")
    assert out.returncode == 0 and failed == 0, out.stdout[-5000:]
    assert "binaries\\" in out.stdout or passed > 0
    # Skips: the native checks (no C host for Windows here), the clock check of an FMU without
    # clocks, the structural-parameter check of an FMU without them, the Scheduled Execution
    # check of an FMU without <ScheduledExecution>, the reference-results check of an FMU that ships
    # none (FMI-LS-REF; the Pendulum's documentation run starts off its start values, so cargo fmu
    # build writes no reference results for it, issue 51).
    not_declared = (
        "not declared by the FMU: <Clock> variables",
        "not declared by the FMU: structural parameters",
        "not declared by the FMU: <ScheduledExecution>",
        "not declared by the FMU: reference results",
    )
    others = [l for l in out.stdout.splitlines()
              if l.startswith("SKIP") and NATIVE not in l and not any(n in l for n in not_declared)]
    assert not others, others
    assert passed >= (15 if fmi3 else 40), summary


# -- A container FMU (cargo fmu container): its Windows binary loads the components' DLLs --


@pytest.mark.parametrize("fmi3", [False, True], ids=["fmi2", "fmi3"])
def test_the_container_of_the_closed_loop_runs_on_windows_as_on_linux(hosts, fmi3):
    """PendulumLQR as one FMU (target/fmu/containers/, FMI 3.0 in containers/fmi3/, made by the
    main job and tests/run.sh with every platform its components carry): under wine its win64
    binary unpacks nothing, loads the Pendulum's and the Controller's win64 DLLs from its
    resources and steps them; 1,000 steps equal the linux64 binary's to 1e-12."""
    fmu = FMU_DIR / "containers" / ("fmi3" if fmi3 else "") / "PendulumLQR.fmu"
    assert fmu.exists(), f"{fmu} is missing: run `bash tests/run.sh` (or the main job) first"
    a, b, seconds = linux_and_windows(hosts, "PendulumLQR", fmi3, [], fmu=fmu)
    d = largest_difference(a, b)
    scale = max(1.0, max(abs(x) for row in a for x in row))
    report(
        f"PendulumLQR container FMI {'3.0' if fmi3 else '2.0'}, {STEPS} steps: largest |linux - windows| = {d:.3g} "
        f"(wine run {seconds:.1f} s)"
    )
    assert d <= 1e-12 * scale, d
    assert a[-1] != a[0], "the loop did not move"
