"""The packaged Pendulum.fmu as users meet it: fmpy's validator, fmutool's checker, fmpy simulations
against an independent reference solution of equations (6)-(7), the fmpy command line, refused
parameters, and the binary's exported and needed symbols."""

import csv
import pathlib
import shutil
import subprocess
import sys
import tempfile
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy.validation import validate_fmu

import paper_model
from conftest import fmu
from fmi_harness import value_after_a_refused_set

STATE = ["alpha1", "omega1", "alpha2", "omega2"]


def simulate(path, x0=(0.0, 0.0, 0.0, 0.0), stop=1.0, h=1e-3, M1=0.0, M2=0.0, **kwargs):
    start = {f"{s}_0": v for s, v in zip(STATE, x0)}  # the initial state: parameters alpha1_0..omega2_0
    inputs = np.array([(0.0, M1, M2)], dtype=[("time", float), ("M1", float), ("M2", float)])
    return fmpy.simulate_fmu(
        path, stop_time=stop, output_interval=h, step_size=h, start_values=start, input=inputs, **kwargs
    )


def max_state_error(result, x0, M1=0.0, M2=0.0):
    ref = paper_model.reference(x0, result["time"], M1=M1, M2=M2)
    got = np.column_stack([result[n] for n in STATE])
    return np.abs(got - ref).max()


def test_fmpy_validation_finds_no_problems(pendulum_fmu):
    assert validate_fmu(pendulum_fmu) == []


def test_fmutool_check_passes(pendulum_fmu):
    fmutool = pathlib.Path(sys.executable).with_name("fmutool")
    out = subprocess.run([str(fmutool), "-input", pendulum_fmu, "-check"], capture_output=True, text=True)
    text = out.stdout + out.stderr
    assert out.returncode == 0, text
    assert "compliant with FMI-2.0" in text and "No semantic error" in text, text


def test_figure6_open_loop_falls_under_one_newton_metre(pendulum_fmu):
    # Figure 6: from rest, M1 = M2 = 1 N.m; the unstable pendulum's angles run away.
    r = simulate(pendulum_fmu, stop=1.0, M1=1.0, M2=1.0)
    assert max_state_error(r, (0, 0, 0, 0), M1=1.0, M2=1.0) < 1e-8
    assert abs(r["alpha1"][-1]) > 1.0 and abs(r["alpha2"][-1]) > 1.0, r[-1]


def test_run_from_alpha1_0p1_matches_reference_to_1e_8(pendulum_fmu):
    r = simulate(pendulum_fmu, x0=(0.1, 0.0, 0.0, 0.0), stop=1.0)
    err = max_state_error(r, (0.1, 0.0, 0.0, 0.0))
    assert err < 1e-8, f"max |FMU - DOP853(1e-12)| over 1 s = {err}"


@pytest.mark.parametrize("seed", range(6))
def test_any_initial_state_matches_reference_to_1e_8(pendulum_fmu, seed):
    rng = np.random.default_rng(seed)
    x0 = (rng.uniform(-np.pi, np.pi), rng.uniform(-5, 5), rng.uniform(-np.pi, np.pi), rng.uniform(-5, 5))
    r = simulate(pendulum_fmu, x0=x0, stop=1.0)
    err = max_state_error(r, x0)
    assert err < 1e-8, f"x0 = {x0}: max error {err} over 1 s"


def test_energy_is_constant_without_torque(pendulum_fmu):
    x0 = (3.0, -4.0, -2.0, 5.0)
    r = simulate(pendulum_fmu, x0=x0, stop=1.0)
    assert abs(r["energy"][0] - paper_model.energy(x0)) < 1e-12
    drift = np.abs(r["energy"] - r["energy"][0]).max()
    assert drift < 1e-8, f"energy drifted by {drift} J"


@pytest.mark.parametrize("h,stop", [(1e-6, 0.01), (1e-5, 0.05), (1e-4, 0.2), (1e-2, 1.0), (0.1, 1.0)])
def test_any_communication_step_from_1e_6_to_0p1_is_accurate(pendulum_fmu, h, stop):
    x0 = (0.5, 1.0, -0.4, -2.0)
    r = simulate(pendulum_fmu, x0=x0, stop=stop, h=h)
    assert r["time"][-1] == pytest.approx(stop)
    err = max_state_error(r, x0)
    assert err < 1e-8, f"h = {h}: max error {err}"


def test_fmpy_command_line_simulates(pendulum_fmu, tmp_path):
    out = tmp_path / "result.csv"
    fmpy_cli = pathlib.Path(sys.executable).with_name("fmpy")
    run = subprocess.run(
        [str(fmpy_cli), "simulate", pendulum_fmu, "--stop-time", "0.5", "--output-interval", "0.01",
         "--start-values", "alpha1_0", "0.1", "--output-file", str(out)],
        capture_output=True, text=True,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    rows = list(csv.DictReader(open(out)))
    assert len(rows) == 51, len(rows)
    assert float(rows[0]["alpha1"]) == pytest.approx(0.1)
    ref = paper_model.reference((0.1, 0, 0, 0), np.array([0.0, 0.5]))
    assert float(rows[-1]["alpha1"]) == pytest.approx(ref[-1][0], abs=1e-8)


@pytest.mark.parametrize("name,value", [("m1", 0.0), ("m2", -0.5), ("l1", -1.0), ("l2", 0.0),
                                        ("m1", float("nan")), ("l2", float("inf")), ("g", float("-inf"))])
def test_nonsense_parameter_is_refused_with_a_message_naming_it(pendulum_fmu, name, value):
    # Nothing was stored: the run goes on with the default value.
    kept = value_after_a_refused_set(pendulum_fmu, name, value)
    assert kept == {"m1": 0.5, "m2": 0.5, "l1": 1.0, "l2": 1.0, "g": 9.81}[name]


def _extract_so(path, tmp_path):
    with zipfile.ZipFile(path) as z:
        names = z.namelist()
        assert "modelDescription.xml" in names and "binaries/linux64/Pendulum.so" in names, names
        z.extract("binaries/linux64/Pendulum.so", tmp_path)
    return tmp_path / "binaries/linux64/Pendulum.so"


def test_binary_exports_the_fmi_functions_only_and_needs_only_the_c_runtime(pendulum_fmu, tmp_path):
    so = _extract_so(pendulum_fmu, tmp_path)
    defined = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True)
    symbols = [l.split()[-1] for l in defined.stdout.splitlines() if l.split()[1] in "TDB"]
    assert symbols and all(s.startswith(("fmi2", "fmi3")) for s in symbols), symbols
    # One binary serves both FMI versions: the 75 functions of fmi3Functions.h beside FMI 2.0's.
    assert len([s for s in symbols if s.startswith("fmi3")]) == 75, symbols
    exported = [s for s in symbols if s.startswith("fmi2")]
    # The 44 functions of FMI 2.0 model exchange and co-simulation (34 of them common or
    # co-simulation, 10 model exchange only): both interfaces are in this one binary.
    me_only = {
        "fmi2EnterEventMode", "fmi2NewDiscreteStates", "fmi2EnterContinuousTimeMode",
        "fmi2CompletedIntegratorStep", "fmi2SetTime", "fmi2SetContinuousStates", "fmi2GetDerivatives",
        "fmi2GetEventIndicators", "fmi2GetContinuousStates", "fmi2GetNominalsOfContinuousStates",
    }
    assert len(exported) == 44 and me_only <= set(exported), sorted(exported)
    needed = subprocess.run(["readelf", "-d", str(so)], capture_output=True, text=True, check=True).stdout
    libs = sorted(l.split("[")[1].split("]")[0] for l in needed.splitlines() if "(NEEDED)" in l)
    allowed = {"libc.so.6", "libm.so.6", "libdl.so.2", "libpthread.so.0", "libgcc_s.so.1", "ld-linux-x86-64.so.2"}
    assert set(libs) <= allowed, libs
    ldd = subprocess.run(["ldd", "-r", str(so)], capture_output=True, text=True)
    assert "undefined symbol" not in ldd.stdout + ldd.stderr, ldd.stdout + ldd.stderr
