"""Error-controlled communication steps in the native runner (issue 26): each step made whole and
as two halves from the same FMU states, the difference of the connected outputs estimating the
coupling error; a step over the tolerance set back (every FMU through its FMU state) and made
again shorter. Accuracy per cost against fixed steps is a benchmark (bench/adaptive-steps); here:
what the runs do."""

import io
import re
import warnings
import zipfile

import numpy as np
import pytest
from test_runner import cli, ssp

import rustfmu_runner

REC = ["pendulum.alpha1", "pendulum.alpha2"]


def deviation(r, ref):
    return max(np.max(np.abs(np.interp(r["time"], ref["time"], ref[x]) - r[x])) for x in REC)


def test_tighter_tolerances_are_more_accurate_and_the_run_ends_at_the_stop_time():
    s = rustfmu_runner.System(ssp("PendulumLQR"))
    ref = s.run(1.0, 5e-5, record=REC)
    errors = {}
    for tol in [1e-3, 1e-5]:
        r = s.run(1.0, 1e-3, record=REC, tolerance=tol)
        made = s.last_run
        t = r["time"]
        assert t[0] == 0.0 and t[-1] == 1.0 and np.all(np.diff(t) > 0)
        # Every attempt is three steps (whole, two halves); the accepted ones are the points.
        assert made["fmu_steps"] == 3 * (len(t) - 1 + made["rejected"]) and made["note"] is None
        errors[tol] = deviation(r, ref)
    assert errors[1e-5] < errors[1e-3] / 3, errors
    # The steps follow the error: few at 1e-3, more at 1e-5.
    assert errors[1e-5] < 2e-4


def test_a_rejected_step_is_made_again_shorter():
    s = rustfmu_runner.System(ssp("PendulumLQR"))
    r = s.run(0.5, 0.25, record=REC, tolerance=1e-6)
    assert s.last_run["rejected"] >= 1
    assert r["time"][1] < 0.25 and r["time"][-1] == 0.5


def test_the_whole_step_that_estimates_the_error_leaves_no_trace():
    """Steps held at 2 ms (min = max) and every one accepted: each is the two 1 ms halves made
    after the whole 2 ms step was set back, so the run equals fixed 1 ms steps at the even points:
    setting the FMU states back restores every component, inputs included. Equal to 1e-15, not
    bit for bit: the adaptive run's times are sums of its steps (t + h, t + h/2), the fixed run's
    k h, a few ulps apart (a trace of the whole step would be ~1e-4)."""
    s = rustfmu_runner.System(ssp("PendulumMotors"))
    rec = REC + ["motor1.tau", "controller.M1"]
    a = s.run(1.0, 2e-3, record=rec, tolerance=1e9, min_step=2e-3, max_step=2e-3)
    assert s.last_run["rejected"] == 0 and len(a["time"]) == 501
    b = s.run(1.0, 1e-3, record=rec)
    assert np.max(np.abs(a["time"] - b["time"][::2])) < 1e-14
    for x in rec:
        scale = max(1.0, np.max(np.abs(b[x])))
        assert np.max(np.abs(a[x] - b[x][::2])) <= 1e-14 * scale, x


def without_fmu_state(path, tmp_path):
    """The SSP file with the Pendulum's modelDescription.xml saying canGetAndSetFMUstate="false"."""
    out = tmp_path / "NoState.ssp"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(out, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename.endswith("Pendulum.fmu"):
                inner = io.BytesIO()
                with zipfile.ZipFile(io.BytesIO(data)) as f, zipfile.ZipFile(inner, "w") as g:
                    for i in f.infolist():
                        d = f.read(i.filename)
                        if i.filename == "modelDescription.xml":
                            d, n = re.subn(rb'canGetAndSetFMUstate="true"', b'canGetAndSetFMUstate="false"', d)
                            assert n >= 1
                        g.writestr(i, d)
                data = inner.getvalue()
            dst.writestr(item, data)
    return str(out)


def test_a_system_that_cannot_set_its_states_back_runs_fixed_steps_and_says_why(tmp_path):
    s = rustfmu_runner.System(without_fmu_state(ssp("PendulumLQR"), tmp_path))
    with pytest.warns(RuntimeWarning, match="component 'pendulum' cannot get and set its FMU state"):
        a = s.run(0.5, 1e-3, record=REC, tolerance=1e-5)
    assert "fixed steps" in s.last_run["note"]
    b = s.run(0.5, 1e-3, record=REC)
    assert s.last_run["note"] is None
    for x in REC:
        assert np.array_equal(a[x], b[x])
    out = cli("run", s.path, "--stop-time", "0.1", "--step", "1e-3", "--tolerance", "1e-5", "--record", "pendulum.alpha1", "--no-progress")
    assert out.returncode == 0 and "cannot get and set its FMU state" in out.stderr, out.stderr


def test_the_command_line_takes_a_tolerance(tmp_path):
    csv = tmp_path / "out.csv"
    out = cli("run", ssp("PendulumLQR"), "--stop-time", "0.5", "--step", "1e-3", "--tolerance", "1e-5",
              "--record", "pendulum.alpha1", "--output", csv, "--no-progress")
    assert out.returncode == 0, out.stderr
    assert re.search(r"\d+ points, \d+ fmi2DoStep calls per component, \d+ steps rejected", out.stderr), out.stderr
    data = np.genfromtxt(csv, delimiter=",", names=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = rustfmu_runner.System(ssp("PendulumLQR")).run(0.5, 1e-3, record=["pendulum.alpha1"], tolerance=1e-5)
    assert np.array_equal(data["time"], r["time"]) and np.array_equal(data["pendulumalpha1"], r["pendulum.alpha1"])
    out = cli("run", ssp("PendulumLQR"), "--step", "1e-3", "--min-step", "1e-4", "--no-progress")
    assert out.returncode != 0 and "--tolerance" in out.stderr


def test_the_error_can_be_estimated_on_chosen_variables():
    """error_on: the estimate on the torques the Controller sends (two of the loop's eight
    connected outputs) makes fewer steps than on every connected output, at the same tolerance;
    what is not a Real variable is refused, naming it."""
    s = rustfmu_runner.System(ssp("PendulumMotors"))
    s.run(1.0, 1e-3, record=REC, tolerance=1e-4)
    every = s.last_run["fmu_steps"]
    r = s.run(1.0, 1e-3, record=REC, tolerance=1e-4, error_on=["controller.M1", "controller.M2"])
    assert s.last_run["fmu_steps"] < every / 3 and r["time"][-1] == 1.0
    with pytest.raises(rustfmu_runner.VariableError, match="controller.mode: not a Real variable"):
        s.run(1.0, 1e-3, record=REC, tolerance=1e-4, error_on=["controller.mode"])
    with pytest.raises(rustfmu_runner.VariableError, match="give a tolerance"):
        s.run(1.0, 1e-3, record=REC, error_on=["controller.M1"])
