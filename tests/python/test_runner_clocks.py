"""FMI 3.0 clocks in the native runner (issue 54 item 1): the clocked SampledController
(target/fmu/fmi3/SampledController.fmu: a periodic input clock `sample` of interval Ts = 10 ms,
clocked measurements and torques / voltages) in place of the Controller of the paper's two loops,
run by the rustfmu-runner command line, which instantiates it with eventModeUsed and ticks the
clock at the communication points, against the same loops run by the tests' own fmpy scheduler
(examples/cosim/master.py, FMU3Slave), which does the same with fmpy's calls: every recorded
variable equal at every communication point."""

import csv
import zipfile

import numpy as np
import pytest
from conftest import FMU_DIR, ROOT, fmu3
from test_runner import cli

import sys

sys.path.insert(0, str(ROOT / "examples"))
from cosim.master import simulate  # noqa: E402
from cosim.systems import read_ssp, bind  # noqa: E402

TS = 0.01
STATES = ["alpha1", "omega1", "alpha2", "omega2"]
SYSTEMS = {
    "PendulumLQR": {"pendulum": STATES, "controller": ["M1", "M2"]},
    "PendulumMotors": {"pendulum": STATES, "controller": ["U1", "U2"], "motor1": ["tau"], "motor2": ["tau"]},
}


def clocked_ssp(name: str, tmp_path) -> str:
    """The FMI 3.0 SSP file of `name` with the SampledController as its controller."""
    out = tmp_path / f"{name}Clocked.ssp"
    with zipfile.ZipFile(FMU_DIR / "fmi3" / f"{name}.ssp") as src, zipfile.ZipFile(out, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "resources/Controller.fmu":
                data = (FMU_DIR / "fmi3" / "SampledController.fmu").read_bytes()
            dst.writestr(item, data)
    return str(out)


def run_cli(path, stop, step, record):
    out = pathlib_tmp(path)
    args = ["run", path, "--stop-time", stop, "--step", step, "--no-progress", "-o", out]
    for c, vs in record.items():
        args += [x for v in vs for x in ("--record", f"{c}.{v}")]
    r = cli(*args)
    assert r.returncode == 0, r.stderr
    with open(out) as f:
        rows = list(csv.reader(f))
    head, data = rows[0], np.array(rows[1:], dtype=float)
    return {k: data[:, i] for i, k in enumerate(head)}


def pathlib_tmp(path):
    return str(path) + ".csv"


def fmpy_scheduler(name, stop, step, record):
    system = bind(read_ssp(FMU_DIR / "fmi3" / f"{name}.ssp"), {
        "Pendulum": fmu3("Pendulum"), "Controller": fmu3("SampledController"), "DCMotor": fmu3("DCMotor")}, {})
    return simulate(system, stop, step, record)


@pytest.mark.parametrize("step", [TS, TS / 2], ids=["h=Ts", "h=Ts/2"])
@pytest.mark.parametrize("name", list(SYSTEMS))
def test_the_clocked_loop_in_the_runner_equals_the_fmpy_scheduler_at_every_sample(name, step, tmp_path):
    record = SYSTEMS[name]
    got = run_cli(clocked_ssp(name, tmp_path), 2.0, step, record)
    want = fmpy_scheduler(name, 2.0, step, record)
    assert np.array_equal(got["time"], want["time"])
    for key in want:
        if key == "time":
            continue
        assert np.array_equal(got[key], want[key]), (key, np.max(np.abs(got[key] - want[key])))
    # The controller acts (not a run of zeros) and its outputs change at the ticks only.
    out = record["controller"][0]
    u = got[f"controller.{out}"]
    assert np.max(np.abs(u)) > 0.1
    per = round(TS / step)
    if per > 1:
        assert np.array_equal(u[1::per], u[0:-1:per]), "held between the ticks"
    assert abs(got["pendulum.alpha1"][-1]) < abs(got["pendulum.alpha1"][0])


def test_a_tick_inside_a_communication_step_fails_the_run_naming_the_clock(tmp_path):
    r = cli("run", clocked_ssp("PendulumLQR", tmp_path), "--stop-time", 0.1, "--step", 0.003, "--no-progress",
            "-o", tmp_path / "x.csv")
    assert r.returncode != 0
    assert "clock 'sample' ticks at t = 0.01, inside the communication step" in r.stderr, r.stderr


def test_the_clocked_loop_runs_the_same_in_child_processes_and_with_fixed_steps_under_a_tolerance(tmp_path):
    """--isolate: the clocks' state machine lives in the instance, in its child process; a
    tolerance falls back to fixed steps and says why (the ticks are at communication points)."""
    path = clocked_ssp("PendulumLQR", tmp_path)
    record = SYSTEMS["PendulumLQR"]
    base = run_cli(path, 0.5, TS, record)
    args = ["--record", "pendulum.alpha1", "--record", "controller.M1"]
    r = cli("run", path, "--stop-time", 0.5, "--step", TS, "--no-progress", "--isolate", "-o", tmp_path / "i.csv", *args)
    assert r.returncode == 0, r.stderr
    iso = np.loadtxt(tmp_path / "i.csv", delimiter=",", skiprows=1)
    assert np.array_equal(iso[:, 1], base["pendulum.alpha1"]) and np.array_equal(iso[:, 2], base["controller.M1"])
    r = cli("run", path, "--stop-time", 0.5, "--step", TS, "--tolerance", 1e-6, "--no-progress", "-o", tmp_path / "t.csv", *args)
    assert r.returncode == 0, r.stderr
    assert "component 'controller' has input clocks" in r.stderr + r.stdout, r.stderr
    tol = np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=1)
    assert np.array_equal(tol[:, 1], base["pendulum.alpha1"])


def test_the_python_module_runs_the_clocked_loop_as_the_command_line(tmp_path):
    import rustfmu_runner

    path = clocked_ssp("PendulumLQR", tmp_path)
    record = SYSTEMS["PendulumLQR"]
    want = run_cli(path, 1.0, TS / 2, record)
    got = rustfmu_runner.System(path).run(1.0, TS / 2, record=[f"{c}.{v}" for c, vs in record.items() for v in vs])
    for key in want:
        assert np.array_equal(np.asarray(got[key]), want[key]), key
