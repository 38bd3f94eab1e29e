"""The FMI 3.0 FMUs (target/fmu/fmi3/) beside their FMI 2.0 twins (target/fmu/): the same
declarations and the same equations, so fmpy must give the same trajectories in both interfaces
(co-simulation: the runtime's own step; model exchange: fmpy's CVode and its explicit Euler), the
composed closed loops must run with the 3.0 FMUs in the project's master (examples/cosim/) and
equal the 2.0 loops, and fmpy's validator must accept every 3.0 FMU. docs/fmi3.md gives the
measured differences."""

import csv
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

import fmi_harness  # noqa: F401  (puts examples/ on sys.path)
from conftest import FMU_DIR, ROOT, fmu, fmu3

from cosim import plant_and_controller, plant_motors_controller, simulate  # noqa: E402
from cosim.fmu_log import LogRoute  # noqa: E402
from cosim.master import Loop  # noqa: E402

NAMES = ["Pendulum", "Controller", "DCMotor"]
STATE = ["alpha1", "omega1", "alpha2", "omega2"]
K_NAMES = [f"K{i}{j}" for i in (1, 2) for j in (1, 2, 3, 4)]
TYPE_IN_3 = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String", "Enumeration": "Enumeration"}


def signals(stop, **columns):
    """An fmpy input table: each column a function of time, on 201 points (fmpy interpolates
    linearly between them)."""
    t = np.linspace(0.0, stop, 201)
    names = list(columns)
    return np.array([(ti, *[columns[n](ti) for n in names]) for ti in t], dtype=[("time", float)] + [(n, float) for n in names])


def step_signal(stop, t_step, name, before, after, **others):
    """An input table with `name` stepping from `before` to `after` at t_step (two rows at t_step:
    a discontinuity, which fmpy treats as an input event) and constant `others`."""
    names = [name, *others]
    times = [0.0, t_step, t_step, stop]
    values = [before, before, after, after]
    return np.array([(t, v, *others.values()) for t, v in zip(times, values)],
                    dtype=[("time", float)] + [(n, float) for n in names])


# case: (FMU, start values, input table or None, stop time, output interval, outputs recorded,
# Euler step). The Pendulum from alpha1 = 0.1, alpha2 = -0.05 (the demos' start) with a torque
# step on M1; the Controller in LQR + PID mode (an Enumeration: fmi3SetInt64) with moving measured
# angles; the DCMotor unloaded (the paper's motor, eq. (17)) and coupled (a Boolean: fmi3SetBoolean)
# with a voltage step. Euler's step is bounded by the fastest pole (the unloaded paper motor's
# 4.17e5 /s: h < 4.8e-6 s; tests/python/test_model_exchange.py).
CASES = {
    "pendulum": ("Pendulum", {"alpha1_0": 0.1, "alpha2_0": -0.05},
                 lambda stop: step_signal(stop, 0.5, "M1", 0.0, 0.2, M2=-0.1), 2.0, 1e-3, STATE + ["energy", "x2", "y2"], 1e-4),
    "controller": ("Controller", {"mode": 3},
                   lambda stop: signals(stop, alpha1=lambda t: 0.02 * np.cos(3 * t), omega1=lambda t: -0.06 * np.sin(3 * t),
                                        alpha2=lambda t: -0.015 + 0.01 * t, omega2=lambda t: 0.01,
                                        alpha1_ref=lambda t: 0.01, alpha2_ref=lambda t: -0.005 * (t > 1.0)),
                   2.0, 1e-3, ["M1", "M2", "U1", "U2", "integral1", "integral2", "rate_filter1", "rate_filter2"] + K_NAMES, 1e-3),
    "motor-unloaded": ("DCMotor", {"coupled": False},
                       lambda stop: step_signal(stop, 0.002, "U", 0.0, 6.0, omega=0.0), 0.01, 1e-5, ["i", "omega_m", "tau", "U_applied"], 1e-6),
    "motor-coupled": ("DCMotor", {"coupled": True, "gear_ratio": 200.0, "B": 1e-6},
                      lambda stop: step_signal(stop, 0.002, "U", 0.0, 6.0, omega=0.3), 0.01, 1e-5, ["i", "omega_m", "tau", "U_applied"], 1e-6),
}

# Largest |3.0 - 2.0| over every recorded variable and point that each test allows. Measured
# (`.venv/bin/python tests/python/test_fmi3.py`, docs/fmi3.md): 0.0 in every case, interface and
# loop, bit-identical: the 3.0 functions forward to the same instance core, equations and
# integrator, and fmpy makes the same calls in the same order in both versions.
BOUND = 0.0


def run(path, case, fmi_type, solver=None):
    name, start, inputs, stop, dt, outputs, euler_h = CASES[case]
    kwargs = dict(fmi_type=fmi_type, stop_time=stop, start_values=dict(start), input=inputs(stop), output=outputs)
    if fmi_type == "CoSimulation":
        kwargs.update(output_interval=dt)
    elif solver == "Euler":
        # fmpy's Euler takes one step per output interval (tests/python/test_model_exchange.py).
        kwargs.update(solver="Euler", step_size=euler_h, output_interval=euler_h)
        if name == "DCMotor":
            kwargs["stop_time"] = 0.005
    else:
        kwargs.update(solver="CVode", output_interval=dt, relative_tolerance=1e-10)
    return fmpy.simulate_fmu(path, **kwargs)


def largest_difference(a, b, names):
    assert len(a) == len(b), f"{len(a)} points against {len(b)}"
    assert np.array_equal(a["time"], b["time"]), "the output grids differ"
    return max(float(np.abs(np.asarray(a[n], float) - np.asarray(b[n], float)).max()) for n in names)


# --- the packages ----------------------------------------------------------------------------


def description(path):
    with zipfile.ZipFile(path) as z:
        return ET.fromstring(z.read("modelDescription.xml")), z.namelist()


@pytest.mark.parametrize("name", NAMES)
def test_fmi3_description_says_3_0_with_both_interfaces_and_the_2_0_variables(name):
    root, files = description(fmu3(name))
    assert root.tag == "fmiModelDescription" and root.get("fmiVersion") == "3.0", root.attrib
    assert root.get("instantiationToken"), "no instantiationToken"
    me, cs = root.find("ModelExchange"), root.find("CoSimulation")
    assert me is not None and cs is not None, [e.tag for e in root]
    assert me.get("modelIdentifier") == cs.get("modelIdentifier") == name
    assert f"binaries/x86_64-linux/{name}.so" in files, files
    assert not any(f.startswith("binaries/linux64/") for f in files), files
    # The same variables as the 2.0 twin, under their 3.0 type names, plus the independent time;
    # an array (the Controller's K) is one variable in 3.0 and its elements K[1,1] .. in 2.0.
    old, _ = description(fmu(name))
    v2 = {v.get("name"): (v.get("valueReference"), TYPE_IN_3[next(iter(v)).tag]) for v in old.iter("ScalarVariable")}
    variables = list(root.find("ModelVariables"))
    arrays = {v.get("name"): v for v in variables if v.find("Dimension") is not None}
    assert set(arrays) == ({"K"} if name == "Controller" else set()), set(arrays)
    for a, v in arrays.items():
        rows, cols = (int(d.get("start")) for d in v.findall("Dimension"))
        first = int(v.get("valueReference"))
        elements = {f"{a}[{i},{j}]": (str(first + (i - 1) * cols + j - 1), v.tag)
                    for i in range(1, rows + 1) for j in range(1, cols + 1)}
        assert {n: v2.pop(n) for n in elements} == elements
    v3 = {v.get("name"): (v.get("valueReference"), v.tag) for v in variables if v.get("name") not in arrays}
    independent = [v.get("name") for v in variables if v.get("causality") == "independent"]
    assert independent == ["time"] and variables[0].get("name") == "time", independent
    del v3["time"]
    assert v3 == v2, f"only in 3.0: {set(v3.items()) - set(v2.items())}; only in 2.0: {set(v2.items()) - set(v3.items())}"


@pytest.mark.parametrize("name", NAMES)
def test_fmpy_validator_accepts_the_fmi3_fmu(name):
    assert validate_fmu(fmu3(name)) == []


# --- fmpy's simulate_fmu: the 3.0 FMU against its 2.0 twin ----------------------------------


@pytest.mark.parametrize("interface", ["CoSimulation", "ModelExchange-CVode", "ModelExchange-Euler"])
@pytest.mark.parametrize("case", list(CASES))
def test_fmi3_trajectory_equals_the_fmi2_twin(case, interface):
    fmi_type, _, solver = interface.partition("-")
    name, outputs = CASES[case][0], CASES[case][5]
    new = run(fmu3(name), case, fmi_type, solver or None)
    old = run(fmu(name), case, fmi_type, solver or None)
    assert len(old) > 100, f"{case}: only {len(old)} points"
    for r in (new, old):
        bad = [n for n in outputs if not np.isfinite(np.asarray(r[n], float)).all()]
        assert not bad, f"{case}/{interface}: non-finite values in {bad}"
    moved = [n for n in outputs if np.ptp(np.asarray(old[n], float)) > 0]
    assert moved, f"{case}/{interface}: nothing moved, an uninteresting run"
    diff = largest_difference(new, old, outputs)
    assert diff <= BOUND, f"{case}/{interface}: max |FMI 3.0 - FMI 2.0| = {diff}, bound {BOUND}"


# --- the project's master: the composed closed loops ------------------------------------------


def ssp(name):
    path = FMU_DIR / f"{name}.ssp"
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo run --release -p fmu-build` (it writes the SSP files)")
    return str(path)


def lqr_system(get):
    return plant_and_controller(get("Pendulum"), get("Controller"), ssp=ssp("PendulumLQR"))


def motor_system(get):
    return plant_motors_controller(get("Pendulum"), get("Controller"), get("DCMotor"), ssp=ssp("PendulumMotors"))


LOOPS = {
    "PendulumLQR": (lqr_system, 5.0, {"pendulum": STATE, "controller": ["M1", "M2"] + K_NAMES}),
    "PendulumMotors": (motor_system, 8.0, {"pendulum": STATE, "controller": ["U1", "U2", "M1", "M2"],
                                           "motor1": ["tau", "i"], "motor2": ["tau", "i"]}),
}


@pytest.mark.parametrize("order", ["gauss-seidel", "jacobi"])
@pytest.mark.parametrize("system", list(LOOPS))
def test_composed_loop_of_fmi3_fmus_equals_the_fmi2_loop(system, order):
    build, stop, record = LOOPS[system]
    new = simulate(build(fmu3), stop, 1e-3, record, order=order)
    old = simulate(build(fmu), stop, 1e-3, record, order=order)
    names = [n for n in old if n != "time"]
    diff = largest_difference(new, old, names)
    assert diff <= BOUND, f"{system} ({order}): max |FMI 3.0 loop - FMI 2.0 loop| = {diff}, bound {BOUND}"
    # And it is the loop the composition tests check: the pendulum stands up.
    late = new["time"] >= stop - 1.0
    for a in ("pendulum.alpha1", "pendulum.alpha2"):
        assert np.abs(new[a][late]).max() < 1e-3, f"{system}: {a} did not settle with the FMI 3.0 FMUs"


def test_one_loop_may_mix_fmi2_and_fmi3_fmus():
    """A 3.0 Pendulum with a 2.0 Controller and 2.0 motors: the master takes each FMU's version
    from its modelDescription; the numbers are those of the all-2.0 loop."""
    record = {"pendulum": STATE, "controller": ["U1", "U2"]}
    mixed = simulate(motor_system(lambda n: fmu3(n) if n == "Pendulum" else fmu(n)), 2.0, 1e-3, record)
    old = simulate(motor_system(fmu), 2.0, 1e-3, record)
    diff = largest_difference(mixed, old, [n for n in old if n != "time"])
    assert diff <= BOUND, f"mixed loop against the 2.0 loop: {diff}"


def test_master_reads_fmi3_variables_of_every_type_and_routes_their_messages():
    """Enumeration (Int64), Boolean, Float64 through the master's set/get on 3.0 instances, the
    added `time` variable, and an error of a 3.0 instance reaches the loop's LogRoute with the
    instance's name."""
    messages = []
    route = LogRoute(lambda instance, status, category, text: messages.append((instance, status, text)))
    loop = Loop(motor_system(fmu3), callbacks=route)
    try:
        assert {loop.fmi_version(c) for c in ("pendulum", "controller", "motor1")} == {"3.0"}
        with pytest.raises(FMICallException):
            loop.set("pendulum.l1", -1.0)
        assert any(instance == "pendulum" and status >= 3 and "'l1'" in text for instance, status, text in messages), messages
    finally:
        loop.close()
    # After an fmi3Error the instance is Terminated until fmi3Reset (FMI 3.0, 2.3.1): the run gets
    # new instances.
    loop = Loop(motor_system(fmu3), callbacks=route)
    try:
        seen = {}

        def observe(k, t):
            seen[k] = (loop.get("controller", "mode"), loop.get("motor1", "coupled"), loop.get("motor2", "coupled"),
                       loop.get("pendulum", "m1"), loop.get("pendulum", "alpha1"))
            # The added independent variable: every instance's current time.
            for c in ("pendulum", "controller", "motor1"):
                assert loop.get(c, "time") == pytest.approx(t, abs=1e-15), (c, k, loop.get(c, "time"))
            return True

        loop.run(0.01, 1e-3, {"controller.mode": "PID", "motor1.coupled": False, "pendulum.m1": 0.75}, observe)
        assert seen[0] == (2, False, True, 0.75, 0.1), seen[0]
        assert len(seen) == 11 and seen[10][4] != 0.1, seen
    finally:
        loop.close()
        route.close()


def test_composed_demo_runs_the_fmi3_fmus_with_the_same_numbers(tmp_path):
    """examples/composed_demo.py --fmi-version 3 writes the CSV the default (FMI 2.0) run writes."""
    fmu3("DCMotor")
    rows = {}
    for version in ("2", "3"):
        out = tmp_path / version
        choice = ["--fmi-version", "3"] if version == "3" else []  # FMI 2.0 is the default
        r = subprocess.run(
            [sys.executable, str(ROOT / "examples/composed_demo.py"), "--out", str(out), "--fmu-dir", str(FMU_DIR),
             "--stop", "2", *choice],
            capture_output=True, text=True,
        )
        assert r.returncode == 0, f"composed_demo.py --fmi-version {version} failed:\n{r.stdout}\n{r.stderr}"
        assert f"FMI {version}.0" in r.stdout, r.stdout
        with open(out / "composed_demo.csv") as f:
            rows[version] = list(csv.reader(f))
    assert len(rows["3"]) == 2002 and rows["3"][0] == rows["2"][0]
    new, old = (np.array(rows[v][1:], float) for v in ("3", "2"))
    diff = float(np.abs(new - old).max())
    assert diff <= BOUND, f"composed_demo.py: FMI 3.0 CSV differs from FMI 2.0 by {diff}"


if __name__ == "__main__":
    # The measured differences (docs/fmi3.md): .venv/bin/python tests/python/test_fmi3.py
    for case, (name, *_rest) in CASES.items():
        outputs = CASES[case][5]
        for interface in ("CoSimulation", "ModelExchange-CVode", "ModelExchange-Euler"):
            fmi_type, _, solver = interface.partition("-")
            new, old = run(fmu3(name), case, fmi_type, solver or None), run(fmu(name), case, fmi_type, solver or None)
            same = all(np.array_equal(new[n], old[n]) for n in outputs)
            print(f"{case:15} {interface:20} {len(old):6} points  max |3.0 - 2.0| = {largest_difference(new, old, outputs):.3g}"
                  f"{'  (bit-identical)' if same else ''}")
    for system, (build, stop, record) in LOOPS.items():
        for order in ("gauss-seidel", "jacobi"):
            new, old = (simulate(build(get), stop, 1e-3, record, order=order) for get in (fmu3, fmu))
            names = [n for n in old if n != "time"]
            same = all(np.array_equal(new[n], old[n]) for n in names)
            print(f"{system:15} {order:20} {len(old['time']):6} points  max |3.0 - 2.0| = {largest_difference(new, old, names):.3g}"
                  f"{'  (bit-identical)' if same else ''}")


def test_intermediate_update_in_fmpy_reports_internal_steps_and_returns_early_where_asked():
    """FMI 3.0 intermediate update through fmpy's FMU3Slave (its `intermediateUpdate`
    argument): the Pendulum's integrator tells the callback the end of each accepted internal
    step, time only (no variable may be read or set there), canReturnEarly with
    earlyReturnAllowed; asked at the first call to return at t = 0.0375, fmi3DoStep(0, 0.1)
    returns there with earlyReturn, and the angle equals a step of plain 0.0375 s (to the
    integrator's tolerance); the next step starts there."""
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave

    path = fmu3("Pendulum")
    md = read_model_description(path)
    assert md.coSimulation.providesIntermediateUpdate
    assert md.coSimulation.canReturnEarlyAfterIntermediateUpdate
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipdir = extract(path)
    calls = []
    ask = [True]

    def told(env, time, set_requested, get_allowed, finished, can_return_early, requested, at):
        calls.append((time, set_requested, get_allowed, finished, can_return_early))
        if ask[0]:
            requested[0] = True
            at[0] = 0.0375

    def run(callback, h):
        slave = FMU3Slave(guid=md.guid, unzipDirectory=unzipdir,
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName="iu")
        slave.instantiate(earlyReturnAllowed=True, intermediateUpdate=callback)
        slave.setFloat64([vr["alpha1_0"]], [0.1])
        slave.enterInitializationMode(startTime=0.0)
        slave.exitInitializationMode()
        result = slave.doStep(0.0, h)
        alpha1 = slave.getFloat64([vr["alpha1"]])[0]
        return slave, result, alpha1

    try:
        slave, (event, terminate, early, last), alpha1 = run(told, 0.1)
        assert (event, terminate, early, last) == (False, False, True, 0.0375)
        assert calls and calls[0][0] <= 0.0375, calls
        assert all(c[1:] == (False, False, True, True) for c in calls), calls
        # The next step starts where the early return ended, and the callback sees it too.
        calls.clear()
        ask[0] = False
        assert slave.doStep(0.0375, 0.0625)[2:] == (False, 0.1)
        assert calls and all(0.0375 < c[0] <= 0.1 for c in calls), calls
        slave.freeInstance()

        plain, (_, _, early, last), alpha1_plain = run(None, 0.0375)
        assert (early, last) == (False, 0.0375)
        assert abs(alpha1 - alpha1_plain) < 1e-9, (alpha1, alpha1_plain)
        plain.freeInstance()
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)


@pytest.mark.parametrize("version", [2, 3])
def test_the_pendulums_output_derivatives_are_its_equations(version):
    """fmi2GetRealOutputDerivatives / fmi3GetOutputDerivatives (maxOutputDerivativeOrder = 1),
    through fmpy after 0.25 s of the swinging Pendulum with a torque held: the derivatives of the
    angle and rate outputs are the FMU's own der(..) values bit for bit (the states' rates), the
    joint's position moves as l1 cos(alpha1) omega1, and the energy changes by the power of the
    torques on the generalized coordinates of eqs. (6)-(7), M1 omega1 + M2 omega2 (no friction)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    from fmpy.fmi3 import FMU3Slave

    path = fmu("Pendulum") if version == 2 else fmu3("Pendulum")
    md = read_model_description(path)
    assert int(md.coSimulation.maxOutputDerivativeOrder) == 1
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipdir = extract(path)
    try:
        cls = FMU2Slave if version == 2 else FMU3Slave
        slave = cls(guid=md.guid, unzipDirectory=unzipdir,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="od")
        slave.instantiate()
        get = slave.getReal if version == 2 else slave.getFloat64
        set_ = slave.setReal if version == 2 else slave.setFloat64
        set_([vr["alpha1_0"], vr["alpha2_0"]], [0.3, -0.2])
        if version == 2:
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
        else:
            slave.enterInitializationMode(startTime=0.0)
        slave.exitInitializationMode()
        set_([vr["M1"], vr["M2"]], [0.05, -0.02])
        t = 0.0
        for _ in range(25):
            slave.doStep(t, 0.01)
            t += 0.01
        outputs = ["alpha1", "omega1", "alpha2", "omega2", "x1", "energy"]
        refs = [vr[n] for n in outputs]
        if version == 2:
            d = slave.getRealOutputDerivatives(refs, [1] * len(refs))
        else:
            d = slave.getOutputDerivatives(refs, [1] * len(refs))
        d = dict(zip(outputs, d))
        der = get([vr[f"der({n})"] for n in ("alpha1", "omega1", "alpha2", "omega2")])
        assert [d["alpha1"], d["omega1"], d["alpha2"], d["omega2"]] == der
        a1, w1, w2, l1 = get([vr["alpha1"], vr["omega1"], vr["omega2"], vr["l1"]])
        assert abs(d["x1"] - l1 * np.cos(a1) * w1) < 1e-14
        assert abs(d["energy"] - (0.05 * w1 + -0.02 * w2)) < 1e-12, d["energy"]
        slave.terminate()
        slave.freeInstance()
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)
