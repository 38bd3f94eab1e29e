"""The DCMotor and Controller FMUs on their own: validators, and the motor's equation (17)."""

import subprocess
import sys

import numpy as np
import pytest
import scipy.signal
from conftest import fmu
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

PAPER_MOTOR = dict(L=0.000121, R=2.22, km=0.00449, kb=0.00448, J=2.18e-5, B=9.0946)


@pytest.mark.parametrize("name", ["Controller", "DCMotor"])
def test_fmpy_validator_accepts(name):
    problems = validate_fmu(fmu(name))
    assert problems == [], f"{name}: {problems}"


@pytest.mark.parametrize("name", ["Controller", "DCMotor"])
def test_fmutool_check_passes(name):
    fmutool = pathlib_bin("fmutool")
    r = subprocess.run([fmutool, "-input", fmu(name), "-check"], capture_output=True, text=True)
    out = r.stdout + r.stderr
    assert r.returncode == 0 and "ERROR" not in out, f"fmutool -check on {name} failed ({r.returncode}):\n{out}"


def pathlib_bin(name):
    import pathlib

    return str(pathlib.Path(sys.executable).parent / name)


def eq17_step(p, u0, t):
    """Speed step response of km / (J L s² + (J R + B L) s + (B R + km kb))."""
    den = [p["J"] * p["L"], p["J"] * p["R"] + p["B"] * p["L"], p["B"] * p["R"] + p["km"] * p["kb"]]
    _, y = scipy.signal.step(([p["km"] * u0], den), T=t)
    return y


@pytest.mark.parametrize("B", [PAPER_MOTOR["B"], 1e-6])
@pytest.mark.parametrize("h", [1e-6, 1e-4, 1e-2])
def test_unloaded_speed_step_response_matches_eq17(B, h):
    p = dict(PAPER_MOTOR, B=B, J=1e-6 if B < 1 else PAPER_MOTOR["J"])
    stop = 0.02 if h >= 1e-4 else 2e-3
    start = {"coupled": False, "U": 6.0, "J": p["J"], "B": B}
    r = simulate_fmu(fmu("DCMotor"), stop_time=stop, step_size=h, output_interval=h, start_values=start, output=["omega_m"])
    want = eq17_step(p, 6.0, r["time"])
    scale = abs(want).max()
    err = np.abs(r["omega_m"] - want).max()
    assert err < 1e-6 * scale, f"B = {B}, h = {h}: max |omega_m - eq.(17)| = {err} (scale {scale})"


def test_motor_at_its_defaults_turns_as_eq17_says():
    # Nothing set but the 6 V: the defaults are the paper's unloaded motor (coupled = false), whose
    # speed answers the voltage with eq. (17). Poles -1.83e4 and -4.17e5 /s: settled in 0.3 ms.
    h = 1e-5
    r = simulate_fmu(fmu("DCMotor"), stop_time=2e-3, step_size=h, output_interval=h, start_values={"U": 6.0},
                     output=["omega_m", "tau", "i"])
    want = eq17_step(PAPER_MOTOR, 6.0, r["time"])
    err = np.abs(r["omega_m"] - want).max()
    assert err < 1e-6 * want.max(), f"max |omega_m - eq.(17)| = {err} rad/s (steady speed {want[-1]} rad/s)"
    assert np.all(r["tau"] == 0.0), f"the unloaded motor gives no joint torque, got up to {np.abs(r['tau']).max()} N.m"
    assert r["i"][-1] == pytest.approx(PAPER_MOTOR["B"] * want[-1] / PAPER_MOTOR["km"], rel=1e-6), "i = B omega / km"


def test_paper_motor_dc_gain_uses_20_19_not_27_19():
    r = simulate_fmu(
        fmu("DCMotor"), stop_time=0.01, step_size=1e-3, start_values={"coupled": False, "U": 6.0}, output=["omega_m"]
    )
    final = r["omega_m"][-1]
    assert final == pytest.approx(0.00449 * 6.0 / 20.19003, rel=1e-6), f"steady speed {final} rad/s"
    assert abs(final - 0.00449 * 6.0 / 27.19) > 0.2 * final


def test_supply_limits_voltage_and_gear_multiplies_torque():
    start = {"coupled": True, "U": 100.0, "gear_ratio": 200.0, "B": 1e-6, "omega": 0.0}
    r = simulate_fmu(fmu("DCMotor"), stop_time=0.01, step_size=1e-3, start_values=start, output=["tau", "U_applied"])
    assert r["U_applied"][-1] == 6.0
    stall = 200 * 0.00449 * 6.0 / 2.22
    assert r["tau"][-1] == pytest.approx(stall, rel=1e-9), f"expected the geared stall torque {stall} N.m"
