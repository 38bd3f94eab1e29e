"""Structural parameters set by the system (issue 54, item 1): two StateSpace FMUs whose
sizes (m, n, r) the system sets to other values than their start values (3, 3, 3), written by
`cargo fmu ssp` in SSP 2.0 (the sizes as ssv:UInt64 values, the arrays' ssc:Dimensions of those
sizes), run by the runner, which sets m, n, r in Configuration Mode and sizes the connection
s1.y -> s2.u, the array parameters and the recorded columns by them; against fmpy running the
same FMUs connected by hand, its instances configured the same way (fmi3EnterConfigurationMode,
fmi3SetUInt64, fmi3ExitConfigurationMode).

The StateSpace is this project's re-make of the Reference-FMUs' one (their model identifier,
variable names, value references and start values): the C Reference StateSpace of
../shared/independent (v0.0.41) refuses every structural parameter in Configuration Mode
("Expected nValues >= 2 but was 1", fixed upstream since; test_python_recipes.py), in fmpy as in
the runner (runner/tests/runner.rs checks the runner's message)."""

import shutil
import subprocess

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

from test_runner import cli
from test_runner_fmi3_types import ours, read_csv
from test_ssp2 import CARGO_FMU

STOP, STEP = 1.0, 0.1
# s1: 2 inputs, 2 states, 2 outputs; s2: 2 inputs (s1's outputs), 4 states, 2 outputs.
S1 = dict(m=2, n=2, r=2, A=[[-1.0, 0.5], [0.0, -2.0]], B=[[1.0, 0.0], [0.0, 1.0]], C=[[1.0, 0.0], [0.5, 1.0]],
          D=[[1.0, 0.0], [0.0, 1.0]], x0=[1.0, -1.0])
S2 = dict(m=2, n=4, r=2,
          A=[[-0.5, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, -1.5, 0.0], [0.0, 0.0, 0.0, -2.0]],
          B=[[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.5, -0.5]], C=[[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 1.0]],
          D=[[0.5, 0.0], [0.0, 0.5]], x0=[0.0, 0.0, 0.0, 0.25])


def toml(values):
    return "{ " + ", ".join(f"{k} = {v}" for k, v in values.items()) + " }"


SYSTEMS = f"""[[system]]
name = "Structural"
fmi-version = "3.0"
connections = ["s1.y -> s2.u"]
[[system.component]]
name = "s1"
fmu = "StateSpace"
parameters = {toml(S1)}
[[system.component]]
name = "s2"
fmu = "StateSpace"
parameters = {toml(S2)}
"""


def write(d, systems):
    (d / "fmi3").mkdir(exist_ok=True)
    shutil.copy(ours("StateSpace"), d / "fmi3" / "StateSpace.fmu")
    (d / "systems.toml").write_text(systems)
    out = subprocess.run([str(CARGO_FMU), "fmu", "ssp", "--systems", str(d / "systems.toml"), "--fmu-dir", str(d)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return d / "fmi3" / "Structural.ssp"


def by_hand(tmp_path):
    """fmpy on the two StateSpace FMUs, each configured with its sizes, s1.y into s2.u at each
    communication point (s1 first, the runner's Gauss-Seidel order): s1.y, s2.y and s2.x per row."""
    path = ours("StateSpace")
    md = read_model_description(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extract(path, str(tmp_path / "by_hand"))
    s1, s2 = (FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName=n) for n in ("s1", "s2"))
    for s, values in [(s1, S1), (s2, S2)]:
        s.instantiate()
        s.enterConfigurationMode()
        s.setUInt64([vr["m"], vr["n"], vr["r"]], [values["m"], values["n"], values["r"]])
        s.exitConfigurationMode()
        for name in ("A", "B", "C", "D", "x0"):
            s.setFloat64([vr[name]], list(np.ravel(values[name])))
        s.enterInitializationMode(startTime=0.0)
        s.exitInitializationMode()
    rows, t = [], 0.0
    n = round(STOP / STEP)
    for k in range(n + 1):
        y1 = s1.getFloat64([vr["y"]], nValues=S1["r"])
        s2.setFloat64([vr["u"]], y1)
        rows.append(list(y1) + list(s2.getFloat64([vr["y"]], nValues=S2["r"]))
                    + list(s2.getFloat64([vr["x"]], nValues=S2["n"])))
        if k < n:
            for s in (s1, s2):
                s.doStep(currentCommunicationPoint=t, communicationStepSize=STEP)
            t = (k + 1) * STEP
    for s in (s1, s2):
        s.terminate()
        s.freeInstance()
    return np.array(rows)


def test_the_runner_sets_the_sizes_the_system_gives_as_fmpy_does(tmp_path):
    written = write(tmp_path, SYSTEMS)
    out = tmp_path / "run.csv"
    r = cli("run", written, "--stop-time", STOP, "--step", STEP, "--no-progress", "--output", out,
            "--record", "s1.y", "--record", "s2.y", "--record", "s2.x")
    assert r.returncode == 0, r.stderr
    got = read_csv(out)
    columns = [f"s1.y[{i}]" for i in (1, 2)] + [f"s2.y[{i}]" for i in (1, 2)] + [f"s2.x[{i}]" for i in (1, 2, 3, 4)]
    assert [k for k in got if k != "time"] == columns
    rows = np.column_stack([got[c] for c in columns])
    ref = by_hand(tmp_path)
    assert rows.shape == ref.shape == (11, 8) and np.max(np.abs(rows - ref)) <= 1e-12, (rows, ref)
    # Not trivially equal: s1's outputs reached s2 (y2 = C2 x2 + 0.5 y1 at t = 0) and s2's four
    # states moved.
    assert np.allclose(rows[0, 2:4], np.array(S2["C"]) @ S2["x0"] + 0.5 * rows[0, 0:2], rtol=0, atol=1e-15)
    assert np.all(np.abs(rows[-1, 4:] - S2["x0"]) > 1e-3), rows[-1]
    # A run's override of a size the system was built with is refused, naming it.
    r = cli("run", written, "--stop-time", STOP, "--step", STEP, "--no-progress", "--set", "s2.n=3")
    assert r.returncode == 1 and "s2.n" in r.stderr and "(4 in this system)" in r.stderr, r.stderr
