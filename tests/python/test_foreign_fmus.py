"""FMUs nobody here wrote in the native runner (issue 54, item 4): a first-order lag built in the
test with PythonFMU (FMI 2.0) and PythonFMU3 (FMI 3.0), whose binaries need libpython in the
process and name none (the runner finds it and says which), and the FMI 2.0 C Reference FMUs;
each alone against fmusim (the Reference FMUs' own simulator) on the same FMU with the same step,
and in a system with ours against fmusim's runs of the same chain, one component at a time, each
fed the outputs the one before wrote (a solution none of the runner's code computes).

fmusim prints 16 significant digits: a value it writes is the double it computed to a relative
5e-16, so "equal" below is |a - b| <= 1e-15 max(1, |b|) where both masters make the same calls
on the same FMU (the same steps, the same inputs at the same times)."""

import os
import re
import pathlib
import subprocess
import sys
import sysconfig

import numpy as np
import pytest
from conftest import ROOT, fmu
from test_runner import cli
from test_runner_fmi3_types import FMUSIM, INDEPENDENT, as_number, need, read_csv, runner, write_ssp

REF2 = INDEPENDENT / "reference-fmus" / "2.0"

# The lag of both FMUs: dx/dt = (u - x)/T, y = x, stepped exactly for the input held over the step
# (x(t + h) = u + (x(t) - u) exp(-h/T)), so that a constant input gives y = u (1 - exp(-t/T)).
LAG = {
    "2.0": ("pythonfmu", "Lag2", '''
import math
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class Lag2(Fmi2Slave):
    description = "first-order lag dx/dt = (u - x)/T, y = x"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.T = 0.5
        self.x0 = 0.0
        self.u = 0.0
        self.y = 0.0
        self.register_variable(Real("T", causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed))
        self.register_variable(Real("x0", causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed))
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def exit_initialization_mode(self):
        self.y = self.x0

    def do_step(self, current_time, step_size):
        self.y = self.u + (self.y - self.u) * math.exp(-step_size / self.T)
        return True
'''),
    "3.0": ("pythonfmu3", "Lag3", '''
import math
from pythonfmu3 import Fmi3Causality, Fmi3Slave, Fmi3Variability, Float64


class Lag3(Fmi3Slave):
    description = "first-order lag dx/dt = (u - x)/T, y = x"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.time = 0.0
        self.T = 0.5
        self.x0 = 0.0
        self.u = 0.0
        self.y = 0.0
        self.register_variable(Float64("time", causality=Fmi3Causality.independent,
                                       variability=Fmi3Variability.continuous))
        self.register_variable(Float64("T", causality=Fmi3Causality.parameter, variability=Fmi3Variability.fixed))
        self.register_variable(Float64("x0", causality=Fmi3Causality.parameter, variability=Fmi3Variability.fixed))
        self.register_variable(Float64("u", causality=Fmi3Causality.input))
        self.register_variable(Float64("y", causality=Fmi3Causality.output))

    def exit_initialization_mode(self):
        self.y = self.x0

    def do_step(self, current_time, step_size):
        self.y = self.u + (self.y - self.u) * math.exp(-step_size / self.T)
        self.time = current_time + step_size
        return True
'''),
}


def libpython() -> str:
    """This Python's shared library (what fmusim, which loads FMUs without it, gets as LD_PRELOAD)."""
    path = pathlib.Path(sysconfig.get_config_var("LIBDIR")) / sysconfig.get_config_var("INSTSONAME")
    if not path.exists():
        pytest.skip(f"{sys.executable} has no shared libpython ({path}): PythonFMU binaries need one")
    return str(path)


@pytest.fixture(scope="session")
def lag_fmus(tmp_path_factory) -> dict:
    """The lag as FMI 2.0 and 3.0 co-simulation FMUs, built with `pythonfmu build` and
    `pythonfmu3 build` (about a second each)."""
    out = tmp_path_factory.mktemp("pythonfmu")
    fmus = {}
    for version, (tool, name, source) in LAG.items():
        script = out / f"{name}.py"
        script.write_text(source)
        r = subprocess.run([sys.executable, "-m", tool, "build", "-f", str(script), "-d", str(out)],
                           capture_output=True, text=True, timeout=120)
        assert r.returncode == 0 and (out / f"{name}.fmu").exists(), r.stdout + r.stderr
        fmus[version] = str(out / f"{name}.fmu")
    return fmus


def fmusim(tmp_path, fmu, stop, step, *args, name="fmusim") -> dict:
    """fmusim on `fmu` (co-simulation, output every step), libpython preloaded for a PythonFMU."""
    out = tmp_path / f"{name}.csv"
    env = dict(os.environ, LD_PRELOAD=libpython())
    r = subprocess.run([need(FMUSIM), "--interface-type", "cs", "--stop-time", str(stop), "--output-interval", str(step),
                        "--output-file", str(out), *map(str, args), fmu], capture_output=True, text=True, timeout=120,
                       env=env)
    assert r.returncode == 0, r.stdout + r.stderr
    return read_csv(out)


def close(got, ref, what):
    got, ref = np.asarray(got, dtype=float), np.asarray(ref, dtype=float)
    assert got.shape == ref.shape, (what, got.shape, ref.shape)
    err = np.abs(got - ref) / np.maximum(1.0, np.abs(ref))
    assert np.max(err) <= 1e-15, (what, int(np.argmax(err)), got[np.argmax(err)], ref[np.argmax(err)])


def as_csv(path, columns: dict):
    """A CSV fmusim reads as --input-file: columns by name, the first 'time'."""
    names = list(columns)
    rows = zip(*[columns[n] for n in names])
    path.write_text(",".join(f'"{n}"' for n in names) + "\n" + "".join(",".join(repr(float(x)) for x in row) + "\n"
                                                                     for row in rows))
    return path


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_a_pythonfmu_lag_alone_equals_fmusim_and_its_exact_solution(lag_fmus, version, tmp_path):
    """The runner loads the libpython of python3 on PATH itself and says which and why; the lag
    with T = 0.25 (a fixed parameter, set) and u = 1 equals fmusim's run of it and
    y = 1 - exp(-t/T)."""
    fmu = lag_fmus[version]
    ssp = write_ssp(tmp_path / "Lag.ssp", [("lag", fmu)])
    out = tmp_path / "runner.csv"
    r = cli("run", ssp, "--stop-time", 1.0, "--step", 0.05, "--set", "lag.u=1", "--set", "lag.T=0.25",
            "--no-progress", "--output", out)
    assert r.returncode == 0, r.stderr
    loaded = re.search(r"rustfmu-runner: loaded (/\S+/libpython3\.\d+\.so\S*) \(RTLD_GLOBAL\) before \S+: it calls "
                       r"the Python C API \(_Py_NoneStruct, ", r.stderr)
    assert loaded and pathlib.Path(loaded[1]).exists(), r.stderr
    assert "found by python3 (" in r.stderr and "--preload-lib PATH" in r.stderr, r.stderr
    got = read_csv(out)
    ref = fmusim(tmp_path, fmu, 1.0, 0.05, "--start-value", "u", 1, "--start-value", "T", 0.25)
    close(got["time"], ref["time"], "time")
    close(got["lag.y"], ref["y"], "y")
    exact = 1.0 - np.exp(-ref["time"] / 0.25)
    # 20 steps, each a product and a sum rounded: a few ulp.
    assert np.max(np.abs(got["lag.y"] - exact)) <= 1e-15 * 20, np.max(np.abs(got["lag.y"] - exact))
    assert got["lag.y"][-1] > 0.98


@pytest.mark.skipif(not pathlib.Path("/dev/shm").is_dir(), reason="isolation runs on Linux")
def test_without_a_libpython_the_error_names_the_symbol_and_the_option_and_the_option_works(lag_fmus, tmp_path):
    ssp = write_ssp(tmp_path / "Lag.ssp", [("lag", lag_fmus["2.0"])])
    args = ["run", ssp, "--stop-time", 0.2, "--step", 0.1, "--set", "lag.u=2", "--no-progress"]
    env = dict(os.environ, RUSTFMU_RUNNER_PYTHON="/bin/false")
    r = subprocess.run([str(ROOT / "target" / "release" / "rustfmu-runner"), *map(str, args)], capture_output=True,
                       text=True, timeout=120, env=env)
    assert r.returncode == 1, r.stderr
    for text in ["component 'lag'", "needs the symbol _Py_NoneStruct of the Python C library",
                 "no libpython was found (/bin/false: exit status: 1)", "--preload-lib /path/to/libpython3.X.so.1.0"]:
        assert text in r.stderr, (text, r.stderr)
    # Given: loaded here and in each isolated component's process, without a word.
    rows = {}
    for isolate in ([], ["--isolate"], ["--isolate", "system"]):
        r = subprocess.run([str(ROOT / "target" / "release" / "rustfmu-runner"), "--preload-lib", libpython(),
                            *map(str, args), *isolate], capture_output=True, text=True, timeout=120, env=env)
        assert r.returncode == 0 and "loaded" not in r.stderr, (isolate, r.stderr)
        rows[tuple(isolate)] = r.stdout
    assert len(set(rows.values())) == 1, rows
    assert abs(float(rows[()].splitlines()[-1].split(",")[1]) - 2 * (1 - np.exp(-0.2 / 0.5))) <= 1e-15, rows
    r = cli("--preload-lib", tmp_path / "nothing.so", *args)
    assert r.returncode == 1 and f"--preload-lib {tmp_path / 'nothing.so'}: " in r.stderr, r.stderr


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_a_pythonfmu_lag_fed_by_our_dc_motor_fed_by_the_reference_dahlquist_equals_fmusim(lag_fmus, version,
                                                                                          tmp_path):
    """Reference Dahlquist's x (FMI 2.0, C) -> our DCMotor's U (FMI 2.0, Rust; unloaded) -> its
    omega_m -> the PythonFMU lag's u. fmusim runs the chain one FMU at a time, each with the
    outputs the one before wrote as its input file (fmusim sets an input at each step's start
    to the file's value at that time, as the runner sets the connected output's)."""
    dahlquist = need(REF2 / "Dahlquist.fmu")
    motor = fmu("DCMotor")
    ssp = write_ssp(tmp_path / "Chain.ssp", [("d", dahlquist), ("motor", motor), ("lag", lag_fmus[version])],
                    [("d", "x", "motor", "U"), ("motor", "omega_m", "lag", "u")])
    stop, step = 2.0, 0.01
    got = runner(tmp_path, ssp, stop, step, "--set", "lag.T=0.1", "--record", "d.x", "--record", "motor.omega_m",
                 "--record", "lag.y")
    first = fmusim(tmp_path, dahlquist, stop, step, name="d")
    second = fmusim(tmp_path, motor, stop, step, "--input-file",
                    as_csv(tmp_path / "U.csv", {"time": first["time"], "U": first["x"]}),
                    "--output-variable", "omega_m", name="motor")
    third = fmusim(tmp_path, lag_fmus[version], stop, step, "--start-value", "T", 0.1, "--input-file",
                   as_csv(tmp_path / "u.csv", {"time": second["time"], "u": second["omega_m"]}), name="lag")
    close(got["d.x"], first["x"], "d.x")
    close(got["motor.omega_m"], second["omega_m"], "motor.omega_m")
    close(got["lag.y"], third["y"], "lag.y")
    assert np.max(got["lag.y"]) > 0.1 * np.max(got["motor.omega_m"]) > 0


# Each FMI 2.0 Reference FMU, its DefaultExperiment's stop time and step (0.1 where it gives none).
# Stair to 8.8 s: at t = 9 its counter reaches 10 and its fmi2DoStep answers fmi2Discard with
# fmi2Terminated true (FMI 2.0.5, 4.2.3: the slave wants to terminate the simulation); fmusim ends
# the run there, the runner fails it (runner/README.md, "FMUs of other exporters").
REFERENCE_2 = {"BouncingBall": (3.0, 0.01), "Dahlquist": (10.0, 0.1), "Feedthrough": (2.0, 0.1), "Stair": (8.8, 0.2),
               "VanDerPol": (20.0, 0.01), "Resource": (1.0, 0.1)}


@pytest.mark.parametrize("name", list(REFERENCE_2))
def test_each_fmi2_reference_fmu_alone_equals_fmusim(name, tmp_path):
    fmu = need(REF2 / f"{name}.fmu")
    stop, step = REFERENCE_2[name]
    got = runner(tmp_path, write_ssp(tmp_path / "R.ssp", [("r", fmu)]), stop, step)
    ref = fmusim(tmp_path, fmu, stop, step)
    close(got["time"], ref["time"], "time")
    outputs = [k for k in got if k != "time"]
    # Every output the runner records (Real, Integer, Boolean, Enumeration; fmusim adds String).
    assert outputs and all(f"r.{k}" in got for k in ref if k not in ("time", "String_output")), (list(got), list(ref))
    for k in outputs:
        want = ref[k[2:]]
        close(got[k], [as_number(x) for x in want] if isinstance(want, list) else want, k)


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_the_python_module_runs_a_pythonfmu_in_the_python_it_runs_in(lag_fmus, version, tmp_path):
    """In a Python process libpython is there already (the runner loads none): the rows of the
    command line's run."""
    import rustfmu_runner

    ssp = write_ssp(tmp_path / "Lag.ssp", [("lag", lag_fmus[version])])
    r = rustfmu_runner.System(ssp).run(0.5, 0.1, start={"lag.u": 3.0})
    ref = runner(tmp_path, ssp, 0.5, 0.1, "--set", "lag.u=3")
    assert np.array_equal(r["lag.y"], ref["lag.y"]) and r["lag.y"][-1] > 1.5, (r, ref)
