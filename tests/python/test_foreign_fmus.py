"""FMUs nobody here wrote in the native runner (issue 54, item 4): a first-order lag built in the
test with PythonFMU (FMI 2.0) and PythonFMU3 (FMI 3.0), whose binaries need libpython in the
process and name none (the runner finds it and says which), and the FMI 2.0 C Reference FMUs;
each alone against fmusim (the Reference FMUs' own simulator) on the same FMU with the same step,
and in a system with ours against fmusim's runs of the same chain, one component at a time, each
fed the outputs the one before wrote (a solution none of the runner's code computes). Then
`cargo fmu check` on the two lags (issue 51): the failed verdicts that are true defects of
PythonFMU / PythonFMU3 reported, and every other failed verdict one judged here.

fmusim prints 16 significant digits: a value it writes is the double it computed to a relative
5e-16, so "equal" below is |a - b| <= 1e-15 max(1, |b|) where both masters make the same calls
on the same FMU (the same steps, the same inputs at the same times)."""

import json
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
# Stair to its stop time, 10 s: at t = 9 its counter reaches 10 and its fmi2DoStep answers
# fmi2Discard with fmi2Terminated true (FMI 2.0.5, 4.2.3: the slave wants to terminate the
# simulation); fmusim and the runner end the run there, the row at t = 9 the last.
REFERENCE_2 = {"BouncingBall": (3.0, 0.01), "Dahlquist": (10.0, 0.1), "Feedthrough": (2.0, 0.1), "Stair": (10.0, 0.2),
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
@pytest.mark.parametrize("step", [0.2, 0.4])
def test_a_component_that_asks_to_end_the_simulation_ends_the_run_where_fmusim_ends_it(version, step, tmp_path):
    """The Reference Stair asks to end the simulation at t = 9 s (FMI 2.0: fmi2DoStep's
    fmi2Discard with fmi2Terminated true; FMI 3.0: fmi3DoStep's terminateSimulation, FMI 3.0.2
    4.2.1 "the FMU requests to stop the simulation"). The command line ends the run there and exits
    0, its rows those of fmusim over the whole run, the last at t = 9 (with a step of 0.4 s, inside
    the step from 8.8 s: its last successful time, where fmusim writes FMI 3.0's at 9.2); beside it the Reference Dahlquist, stepped to
    that time too, equals fmusim's Dahlquist at every row. The Python module returns the same rows
    with a RuntimeWarning and says who asked in last_run["terminated"]."""
    import rustfmu_runner

    ref_dir = INDEPENDENT / "reference-fmus" / version
    stair, dahlquist = need(ref_dir / "Stair.fmu"), need(ref_dir / "Dahlquist.fmu")
    ssp = write_ssp(tmp_path / "S.ssp", [("stair", stair), ("d", dahlquist)])
    out = tmp_path / "runner.csv"
    r = cli("run", ssp, "--stop-time", 10, "--step", step, "--no-progress", "--output", out)
    assert r.returncode == 0, r.stderr
    assert "component 'stair' asked to terminate the simulation at t = 9 s" in r.stderr, r.stderr
    assert "the rows end at t = 9 s" in r.stderr, r.stderr
    got = read_csv(out)
    ref = fmusim(tmp_path, stair, 10, step, name="stair")
    if version == "3.0" and step == 0.4:
        # fmusim (and fmusim-rs 0.8.0) write FMI 3.0's last row at the step's end, 9.2, where
        # the FMU's lastSuccessfulTime says 9 (FMI 3.0.2 4.2.1): the runner writes 9.
        assert ref["time"][-1] > 9.19, ref["time"][-3:]
        ref["time"][-1] = 9.0
    close(got["time"], ref["time"], "time")
    assert got["time"][-1] == 9.0 and ref["counter"][-1] == 10, (got["time"][-3:], ref["counter"][-3:])
    close(got["stair.counter"], ref["counter"], "counter")
    # fmusim's Dahlquist alone, to the same time: the runner's rows at each of its points.
    d = fmusim(tmp_path, dahlquist, 9, step, name="d")
    close(got["time"], d["time"], "time")
    close(got["d.x"], d["x"], "x")

    system = rustfmu_runner.System(ssp)
    with pytest.warns(RuntimeWarning, match="component 'stair' asked to terminate the simulation at t = 9 s"):
        m = system.run(10.0, step)
    assert np.array_equal(m["time"], got["time"]) and np.array_equal(m["d.x"], got["d.x"])
    end = system.last_run["terminated"]
    assert end["component"] == "stair" and end["time"] == 9.0 and "the run ends there" in end["message"], end
    # A run that no component ends says so too. (A fresh system: the Reference Stair's fmi2Reset
    # keeps its terminateSimulation flag, so a second run of the same instance ends at its first
    # step, fmusim's or ours.)
    system = rustfmu_runner.System(ssp)
    assert system.run(8.0, step)["time"][-1] == 8.0 and system.last_run["terminated"] is None


@pytest.mark.parametrize("case", ["after", "isolate", "event-mode"])
def test_where_the_run_ends_when_a_component_asks_depends_on_where_the_others_are(case, tmp_path):
    """Stair after Dahlquist in the order, a step of 0.4 s: Dahlquist stepped to 9.2 s before
    Stair stopped at 9, and is not taken back, so the rows end at 8.8 s and the message says why.
    Isolated (each in a child process, the step's answer read at the next call): the same rows as
    in-process. FMI 3.0 with --event-mode: Stair returns early at its time event, 9 s, asks to end
    in fmi3UpdateDiscreteStates there, and the last row is at 9 s."""
    version = "2.0" if case == "isolate" else "3.0"
    ref_dir = INDEPENDENT / "reference-fmus" / version
    ssp = write_ssp(tmp_path / "S.ssp", [("d", need(ref_dir / "Dahlquist.fmu")), ("stair", need(ref_dir / "Stair.fmu"))])
    args = {"after": [], "isolate": ["--isolate"], "event-mode": ["--event-mode", "stair"]}[case]
    out = tmp_path / "runner.csv"
    r = cli("run", ssp, "--stop-time", 10, "--step", 0.4, "--no-progress", "--output", out, *args)
    assert r.returncode == 0, r.stderr
    got = read_csv(out)
    if case == "event-mode":
        assert "(in fmi3UpdateDiscreteStates from t = 9 s): the run ends there; the rows end at t = 9 s" in r.stderr
        assert got["time"][-1] == 9.0 and got["stair.counter"][-1] == 10, r.stderr
        # A row at each of Stair's events (every second) besides the grid's.
        assert list(got["stair.counter"][np.isin(got["time"], np.arange(1.0, 10.0))]) == list(range(2, 11)), got
        return
    assert "the rows end at t = 8.8 s (no row at t = 9 s: a component stepped before it had passed" in r.stderr, r.stderr
    assert got["time"][-1] == 8.8 and got["stair.counter"][-1] == 9, (got["time"][-2:], got["stair.counter"][-2:])
    alone = runner(tmp_path, write_ssp(tmp_path / "D.ssp", [("d", str(ref_dir / "Dahlquist.fmu"))]), 8.8, 0.4)
    assert np.array_equal(got["d.x"], alone["d.x"])


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_the_python_module_runs_a_pythonfmu_in_the_python_it_runs_in(lag_fmus, version, tmp_path):
    """In a Python process libpython is there already (the runner loads none): the rows of the
    command line's run."""
    import rustfmu_runner

    ssp = write_ssp(tmp_path / "Lag.ssp", [("lag", lag_fmus[version])])
    r = rustfmu_runner.System(ssp).run(0.5, 0.1, start={"lag.u": 3.0})
    ref = runner(tmp_path, ssp, 0.5, 0.1, "--set", "lag.u=3")
    assert np.array_equal(r["lag.y"], ref["lag.y"]) and r["lag.y"][-1] > 1.5, (r, ref)


# `cargo fmu check` (default verdicts) on the two lags (issue 51). The checker loads the
# libpython of python3 on PATH before the binary itself, as the runner does, and says so in the
# report's head.
# A check failed on them is either a true defect of PythonFMU / PythonFMU3, the standard's
# sentence it rests on given here, or a verdict judged not the FMU's obligation (the importer's
# mistake the standard leaves undefined, or a house rule), left to the checker's owner.
CHECK_TRUE_DEFECTS = {
    "2.0": {
        # Also with a ctypes host: fmi2Instantiate(..., "file:/abs/resources", ...) crashes.
        "instantiate_accepts_every_resource_location_form_and_a_missing_folder":
            'FMI 2.0.5 2.1.5 (fmi2Instantiate): "The following schemes must be understood by the FMU: Mandatory: '
            '\'file\' with absolute path (either including or omitting the authority component)"; PythonFMU 0.7.0 '
            'crashes (SIGSEGV) on file:/<absolute path>',
        # One of its four findings: fmi2GetStatus(fmi2DoStepStatus) outside fmi2Pending answers fmi2Error.
        "every_function_in_every_state_answers_as_the_standard_says":
            'FMI 2.0.5 4.2.3 (fmi2GetXXXStatus): "If a status is required which cannot be retrieved by the slave '
            'it returns fmi2Discard"',
    },
    "3.0": {
        # PySlaveInstance::DoStep writes neither eventHandlingNeeded nor earlyReturn, and
        # terminateSimulation only when do_step returns an object that has one.
        "fmi3_do_step_output_arguments_are_truthful":
            "FMI 3.0.2 4.2.1 (fmi3DoStep): eventHandlingNeeded, terminateSimulation and earlyReturn are the "
            "call's outputs; PythonFMU3 0.3.4 leaves them as the importer's memory held them",
        # fmi3EnterInitializationMode drops its startTime (cppfmu/fmi_functions.cpp): no Python
        # model can know it, so its independent variable reads 0 where the run starts at 0.25.
        "fmi3_the_time_variable_reads_the_current_time_and_cannot_be_set":
            "FMI 3.0.2 2.4.7.4: the independent variable is the time, and fmi3EnterInitializationMode gives its "
            "start (startTime); PythonFMU3 never passes startTime on to the model",
        "fmi3_a_c_host_runs_co_simulation_and_model_exchange_clean_under_valgrind":
            "the same unwritten fmi3DoStep outputs, read by the C host as terminateSimulation = true",
    },
}
CHECK_NOT_THE_STANDARD = {
    "2.0": {
        "instantiate_refuses_a_null_or_empty_instance_name_with_a_message":
            "FMI 2.0.5 2.1.5: 'It is not allowed to provide a null pointer and this string must be non-empty': "
            "the importer's obligation",
        "instantiate_without_callbacks_or_logger_returns_null_without_crashing":
            "callbacks not provided: the importer's mistake (a C++ exception escapes fmi2Instantiate)",
        "unknown_value_references_are_refused_with_a_message_naming_them": "an unknown value reference: the importer's mistake",
        "set_debug_logging_refuses_unknown_categories_and_null_arrays":
            "a category the FMU does not know: the importer's mistake (FMI 2.0.5 2.1.5: the allowed values are "
            "the modeling environment's)",
        "each_instance_logs_to_its_own_component_environment":
            "the FMU logged nothing; FMI 2.0.5 asks no message of it (nothing to judge: a skip)",
        "a_null_component_is_refused_by_every_function": "a NULL instance: the importer's mistake",
        "terminate_twice_is_refused_with_a_message":
            "fmi2Terminate in Terminated is outside the state machine (FMI 2.0.5 4.3.1): the importer's mistake",
        "directional_derivative_flag_is_either_value_and_false_means_refused":
            "refused (fmi2Error) as the flag says; only the message's words are missing: a house rule",
        "random_call_sequences_keep_every_fmu_conformant":
            "fmi2SetBoolean on a Real's value reference answered fmi2Fatal: the importer's mistake",
        "regressions_found_by_random_sequences": "an unknown value reference answered fmi2Fatal: the importer's mistake",
        # Crashes (SIGSEGV) in the checker's process on a legal sequence (steps and status
        # queries), every run; a ctypes host making the same calls in a Python process does not:
        # not decided.
        "status_functions_report_the_last_successful_time_and_no_termination_request": "not decided (see above)",
    },
    "3.0": {
        "fmi3_instantiate_refuses_a_wrong_or_null_token_or_name_and_event_mode_with_null":
            "a wrong instantiationToken: the importer's mistake (FMI 3.0.2 2.3.1)",
        "fmi3_set_debug_logging_refuses_unknown_categories": "an undeclared category: the importer's mistake",
        "fmi3_a_null_instance_is_refused_by_every_function": "a NULL instance: the importer's mistake",
        "fmi3_scheduled_execution_activates_the_partitions_at_their_clocks_and_signals_the_clock_updates":
            "fmi3InstantiateScheduledExecution on an FMU without <ScheduledExecution>: the importer's mistake "
            "(PythonFMU3 throws a C++ exception through it); the check should skip",
        # A message with the category "": FMI 3.0.2 (fmi3LogMessageCallback) leaves the categories to
        # the modeling environment ("none, some or all" declared in <LogCategories>).
        "fmi3_ten_thousand_instantiate_free_cycles_leave_memory_flat": "a log category not declared: not a requirement",
        "fmi3_random_call_sequences_never_crash_and_keep_status_consistent": "the same undeclared log category",
        "fmi3_after_fmi3_error_the_instance_is_terminated_until_reset_or_set_fmu_state": "the same undeclared log category",
        # A C++ exception out of fmi3FreeInstance after calls the FMU refused; not reproduced
        # with a ctypes host: not decided.
        "fmi3_every_type_reads_its_start_sets_reads_back_and_refuses_outside_its_bounds": "not decided",
        "fmi3_variable_dependencies_equal_the_model_structure": "not decided",
        "fmi3_co_simulation_every_function_in_every_state_answers_as_the_standard_says": "not decided",
    },
}


@pytest.fixture(scope="session")
def lag_checks(lag_fmus, tmp_path_factory) -> dict:
    """`cargo fmu check --json` on both lags, side by side (about 30 s)."""
    cargo_fmu = ROOT / "target" / "release" / "cargo-fmu"
    if not cargo_fmu.exists():
        pytest.fail(f"{cargo_fmu} is missing: build it with `cargo build --release -p fmu-build --bins`")
    out = tmp_path_factory.mktemp("check")
    libpython()  # skips where this Python has no shared libpython
    env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    # --timeout 120: the memory check sizes its cycles to a budget from the first ten (a PythonFMU
    # instantiation is slow), and on a loaded CI machine (both lags side by side, two pytest
    # workers, clippy beside them) the cycles then ran slower and the check passed the default
    # 30 s (session 12's CI rehearsal). This test judges verdicts, not the checker's time.
    runs = {v: (out / f"{v}.json", subprocess.Popen([str(cargo_fmu), "fmu", "check", fmu, "--json", str(out / f"{v}.json"),
                                                     "--reproducers", str(out), "--timeout", "120"], env=env,
                                                    stdout=subprocess.PIPE,
                                                    stderr=subprocess.STDOUT, text=True))
            for v, fmu in lag_fmus.items()}
    reports = {}
    for v, (path, p) in runs.items():
        text, _ = p.communicate(timeout=600)
        assert path.exists(), text
        reports[v] = json.loads(path.read_text())
    return reports


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_cargo_fmu_check_loads_the_libpython_a_pythonfmu_needs_and_says_which(lag_checks, version):
    """Without LD_PRELOAD the checker gets past loading and instantiating the lag: it loaded the
    libpython of python3 on PATH (RTLD_GLOBAL) before the binary, and its report's head says which
    and why."""
    report = lag_checks[version]
    assert report["load_error"] is None, report["load_error"]
    said = [a for a in report["about"] if a.startswith("loaded ")]
    assert len(said) == 1, report["about"]
    loaded = re.match(r"loaded (/\S+/libpython3\.\d+\.so\S*) \(RTLD_GLOBAL\) before \S+: it calls the Python C API "
                      r"\(_Py_NoneStruct, .*; found by python3 \(", said[0])
    assert loaded and pathlib.Path(loaded[1]).exists(), said[0]
    verdicts = {c["name"]: c["verdict"] for c in report["checks"]}
    # Past instantiation: an instance initialized and stepped, no failure.
    stepped = "do_step_advances_time_by_the_step" if version == "2.0" else "fmi3_do_step_advances_time_by_the_step"
    assert verdicts.get(stepped) in ("passed", "warned"), (stepped, verdicts.get(stepped))


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_cargo_fmu_check_fails_a_pythonfmu_lag_for_its_true_defects_and_nothing_unjudged(lag_checks, version):
    report = lag_checks[version]
    assert report["load_error"] is None, report["load_error"]
    verdicts = {c["name"]: c["verdict"] for c in report["checks"]}
    failed = {n for n, v in verdicts.items() if v == "failed"}
    missing = set(CHECK_TRUE_DEFECTS[version]) - failed
    assert not missing, f"true defects no longer reported: {missing}"
    unjudged = failed - set(CHECK_TRUE_DEFECTS[version]) - set(CHECK_NOT_THE_STANDARD[version])
    assert not unjudged, {c["name"]: c["message"] for c in report["checks"] if c["name"] in unjudged}
    assert sum(report["totals"].values()) == len(verdicts) and report["totals"]["failed"] == len(failed)
    if version == "2.0":
        # ~10 KB an instance kept after fmi2FreeInstance: a warning (a leak is not the standard's).
        assert verdicts["ten_thousand_instantiate_free_cycles_leave_memory_flat"] == "warned"
