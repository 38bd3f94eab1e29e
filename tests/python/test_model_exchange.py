"""Model exchange and fmi2GetDirectionalDerivative of the packaged Pendulum, Controller and DCMotor:
fmpy's CVode and Euler integrate them; the Pendulum matches co-simulation and an independent
solution of (6)-(7), Euler to its first order; the unloaded motor follows eq. (17); every FMU's
directional derivatives are its Jacobian (central differences, the zeros ModelStructure promises);
refused calls leave the instance usable; examples/linearize.py gets eq. (12) and (14) through them."""

import contextlib
import ctypes
import shutil
import subprocess
import sys

import fmpy
import numpy as np
import pytest
import scipy.signal
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model, FMU2Slave

import fmi_harness  # noqa: F401  (puts examples/ on sys.path)
import paper_model
from conftest import ROOT, fmu
from cosim.fmu_log import LogRoute  # noqa: E402

import linearize  # noqa: E402  (examples/linearize.py)

STATE = ["alpha1", "omega1", "alpha2", "omega2"]
X0 = (0.1, 0.0, 0.0, 0.0)  # the Pendulum's start: alpha1 = 0.1 rad, at rest, no torque
PAPER_MOTOR = dict(L=0.000121, R=2.22, km=0.00449, kb=0.00448, J=2.18e-5, B=9.0946)


def simulate_me(path, solver, stop, start, h=None, **kwargs):
    """fmpy model exchange. fmpy's Euler takes ONE step per output interval (step_size must only
    divide it and is otherwise unused), so for Euler both are set to h."""
    if solver == "Euler":
        kwargs.update(step_size=h, output_interval=h)
    else:
        kwargs.setdefault("output_interval", h or 1e-3)
    return fmpy.simulate_fmu(path, fmi_type="ModelExchange", solver=solver, stop_time=stop, start_values=start, **kwargs)


def states_of(result):
    return np.column_stack([result[n] for n in STATE])


# --- fmpy's simulate_fmu in model exchange ------------------------------------------------------

CONTROLLER_INPUTS = dict(alpha1=0.02, omega1=-0.01, alpha2=-0.015, omega2=0.005, alpha1_ref=0.01, alpha2_ref=-0.005)
K_NAMES = [f"K{i}{j}" for i in (1, 2) for j in (1, 2, 3, 4)]

# case: (FMU, start values, Euler step). Euler's step is bounded by the fastest pole: the unloaded
# paper motor has poles -1.83e4 and -4.17e5 /s (Euler stable below 4.8e-6 s), so the motor runs
# 0.02 s with h = 1e-6 under Euler (2 s would be 2e6 fmpy steps); CVode (BDF) runs every case 2 s.
ME_RUNS = {
    "pendulum": ("Pendulum", {"alpha1_0": 0.1}, 1e-3),
    "controller": ("Controller", dict(CONTROLLER_INPUTS, mode=3), 1e-3),
    "motor-unloaded": ("DCMotor", {"coupled": False, "U": 6.0}, 1e-6),
    "motor-coupled": ("DCMotor", {"coupled": True, "U": 6.0, "omega": 0.3}, 1e-6),
}


def check_final_values(case, solver, r):
    """What each run must end at, from the equations; returns the problems found."""
    last = {n: r[n][-1] for n in r.dtype.names}
    t = last["time"]
    p = PAPER_MOTOR
    want = {}
    if case == "pendulum":
        # Energy (2)-(5) without torque: measured drift over 2 s, CVode rtol 1e-10: 2.7e-7 J;
        # Euler h = 1e-3: 0.31 J of 9.77 J (first order). Bounds 10x.
        found = []
        if abs(r["energy"][0] - paper_model.energy(X0)) > 1e-12:
            found.append(f"initial energy {r['energy'][0]!r}, eq. (2)-(5) give {paper_model.energy(X0)!r}")
        drift = np.abs(r["energy"] - r["energy"][0]).max()
        if drift > {"CVode": 3e-6, "Euler": 3.0}[solver]:
            found.append(f"energy drifted by {drift} J")
        return found
    if case == "controller":
        # LQR + PID with constant inputs: integral_i = e_i t, rate filter = omega_i (it starts at
        # the measured speed), M = -K (x - x_ref) + Kp e + Ki e t - Kd omega; U1, U2 at the 6 V
        # supply limit (U = R/km (M + B omega) is hundreds of volts for these demands).
        s = CONTROLLER_INPUTS
        k = np.array([last[n] for n in K_NAMES]).reshape(2, 4)
        x = np.array([s["alpha1"], s["omega1"], s["alpha2"], s["omega2"]])
        x_ref = np.array([s["alpha1_ref"], 0.0, s["alpha2_ref"], 0.0])
        e = [s["alpha1_ref"] - s["alpha1"], s["alpha2_ref"] - s["alpha2"]]
        pid = [(30.0, 15.0, 5.0), (10.0, 5.0, 5.0)]  # Kp, Ki, Kd defaults of joints 1, 2
        m = -k @ (x - x_ref) + [kp * ei + ki * ei * t - kd * w for (kp, ki, kd), ei, w in zip(pid, e, x[[1, 3]])]
        want = {"integral1": e[0] * t, "integral2": e[1] * t, "rate_filter1": x[1], "rate_filter2": x[3],
                "M1": m[0], "M2": m[1], "U1": np.sign(m[0] + p["B"] * x[1]) * 6.0, "U2": np.sign(m[1] + p["B"] * x[3]) * 6.0}
    elif case == "motor-unloaded":
        # Settled (slowest pole 1.8e4 /s): omega = km U / (B R + km kb), i = B omega / km, tau = 0.
        w = p["km"] * 6.0 / (p["B"] * p["R"] + p["km"] * p["kb"])
        want = {"omega_m": w, "i": p["B"] * w / p["km"], "tau": 0.0, "U_applied": 6.0}
    elif case == "motor-coupled":
        # Settled (pole -R/L): i = (U - kb omega)/R, tau = km i - B omega, omega_m = omega.
        i = (6.0 - p["kb"] * 0.3) / p["R"]
        want = {"i": i, "tau": p["km"] * i - p["B"] * 0.3, "omega_m": 0.3, "U_applied": 6.0}
    return [f"{n} = {float(last[n])!r}, expected {float(v)!r}" for n, v in want.items()
            if not abs(last[n] - v) <= 1e-9 * max(1.0, abs(v))]


@pytest.mark.parametrize("solver", ["CVode", "Euler"])
@pytest.mark.parametrize("case", list(ME_RUNS))
def test_me_simulation_runs_and_ends_where_the_equations_say(case, solver):
    name, start, euler_h = ME_RUNS[case]
    stop = 0.02 if (solver == "Euler" and name == "DCMotor") else 2.0
    extra = {}
    if name == "Controller":
        extra["output"] = ["M1", "M2", "U1", "U2", "integral1", "integral2", "rate_filter1", "rate_filter2"] + K_NAMES
    if solver == "CVode":
        # Tight enough that the settled values are exact to 1e-9 (default rtol 1e-5 leaves the
        # coupled motor's current 3e-5 relative off; 1e-12 exceeds CVode's 500 steps per output
        # interval in the unloaded motor's 2.4 us transient).
        extra["relative_tolerance"] = 1e-10
    r = simulate_me(fmu(name), solver, stop, start, h=euler_h if solver == "Euler" else 1e-3, **extra)
    assert r["time"][-1] == pytest.approx(stop), f"{case}/{solver}: stopped at {r['time'][-1]}"
    bad = [n for n in r.dtype.names if not np.isfinite(r[n]).all()]
    assert not bad, f"{case}/{solver}: non-finite values in {bad}"
    problems = check_final_values(case, solver, r)
    assert not problems, f"{case}/{solver} at t = {stop}: " + "; ".join(problems)


# --- the Pendulum: model exchange vs co-simulation vs (6)-(7) -----------------------------------


@pytest.fixture(scope="module")
def pendulum_cs_2s():
    return fmpy.simulate_fmu(fmu("Pendulum"), fmi_type="CoSimulation", stop_time=2.0, output_interval=1e-3,
                             start_values={"alpha1_0": 0.1}, output=STATE)


# Measured over 2 s from alpha1 = 0.1 (the pendulum falls, alpha2 reaches -11 rad, |omega2| 19 rad/s;
# errors are max over the 2001 points and the 4 states, in rad and rad/s):
#   CVode rtol 1e-10: |ME - DOP853(1e-12)| = 5.73e-6, |ME - CS| = 5.73e-6
#   CVode rtol 1e-12: |ME - DOP853(1e-12)| = 9.2e-8
#   CS (fmi2DoStep, its Dormand-Prince at rtol = atol = 1e-10): |CS - DOP853| = 2.5e-10
# The ME error follows CVode's tolerance (60x smaller for 100x tighter): it is the importer's
# integration error on an unstable trajectory, not a model difference. Bounds: ~10x the measurement.
@pytest.mark.parametrize("rtol,bound", [(1e-10, 6e-5), (1e-12, 1e-6)])
def test_pendulum_me_cvode_matches_cosimulation_and_reference(pendulum_cs_2s, rtol, bound):
    me = simulate_me(fmu("Pendulum"), "CVode", 2.0, {"alpha1_0": 0.1}, h=1e-3, relative_tolerance=rtol, output=STATE)
    cs = pendulum_cs_2s
    assert np.array_equal(me["time"], cs["time"]), "ME and CS output grids differ"
    ref = paper_model.reference(X0, me["time"])
    me_ref = np.abs(states_of(me) - ref).max()
    me_cs = np.abs(states_of(me) - states_of(cs)).max()
    cs_ref = np.abs(states_of(cs) - ref).max()
    assert cs_ref < 3e-9, f"co-simulation vs DOP853(1e-12): {cs_ref} (measured 2.5e-10)"
    assert me_ref < bound, f"ME CVode rtol {rtol} vs DOP853(1e-12): {me_ref}, bound {bound}"
    assert me_cs < bound, f"ME CVode rtol {rtol} vs co-simulation: {me_cs}, bound {bound}"


def euler_run(h, stop=2.0):
    r = simulate_me(fmu("Pendulum"), "Euler", stop, {"alpha1_0": 0.1}, h=h, output=STATE)
    assert len(r) == round(stop / h) + 1, f"h = {h}: {len(r)} points, expected one per Euler step"
    return r


def test_pendulum_me_euler_error_is_first_order():
    # Measured, max over 2 s of |Euler - DOP853(1e-12)|: h = 2e-4: 0.977, 1e-4: 0.499, 5e-5: 0.252
    # (error/h = 4886, 4994, 5046): ratios 1.957, 1.979, tending to 2.
    err = {}
    for h in (2e-4, 1e-4):
        r = euler_run(h)
        err[h] = np.abs(states_of(r) - paper_model.reference(X0, r["time"])).max()
    ratio = err[2e-4] / err[1e-4]
    assert 1.9 < ratio < 2.1, f"halving Euler's step divided its error by {ratio} (errors {err}), not ~2"
    assert err[1e-4] < 1e-4 * 1e4, f"Euler h = 1e-4 error {err[1e-4]} exceeds 1e4 h (measured ~5000 h)"


def test_pendulum_me_euler_is_explicit_euler_of_eq_6_7():
    # The same Euler steps on paper_model.rhs: measured max difference 5.6e-12 over 2 s (10001 steps),
    # i.e. each fmi2GetDerivatives is (6)-(7) to round-off.
    h = 2e-4
    r = euler_run(h)
    x = np.array(X0)
    mine = [x]
    for _ in range(len(r) - 1):
        x = x + h * paper_model.rhs(x)
        mine.append(x)
    diff = np.abs(states_of(r) - np.array(mine)).max()
    assert diff < 1e-10, f"FMU Euler vs Euler on (6)-(7), h = {h}: max difference {diff}"


# --- the unloaded DC motor in model exchange: eq. (17) ------------------------------------------


def eq17_step(p, u0, t):
    """Speed step response of km / (J L s² + (J R + B L) s + (B R + km kb))."""
    den = [p["J"] * p["L"], p["J"] * p["R"] + p["B"] * p["L"], p["B"] * p["R"] + p["km"] * p["kb"]]
    _, y = scipy.signal.step(([p["km"] * u0], den), T=t)
    return y


# Measured max |omega_m - eq.(17)| / max|eq.(17)| over 0.02 s, CVode rtol 1e-12 (atol = rtol, fmpy):
# paper motor 1.5e-9, B = 1e-6 (J = 1e-6) 1.2e-12. Bounds ~10x. (rtol 1e-10: 1.8e-7 and 3.7e-11.)
@pytest.mark.parametrize("B,bound", [(PAPER_MOTOR["B"], 2e-8), (1e-6, 2e-11)])
def test_unloaded_motor_me_speed_step_response_matches_eq17(B, bound):
    p = dict(PAPER_MOTOR, B=B, J=1e-6 if B < 1 else PAPER_MOTOR["J"])
    start = {"coupled": False, "U": 6.0, "J": p["J"], "B": B}
    r = simulate_me(fmu("DCMotor"), "CVode", 0.02, start, output_interval=1e-5, relative_tolerance=1e-12,
                    output=["omega_m"])
    want = eq17_step(p, 6.0, r["time"])
    scale = np.abs(want).max()
    err = np.abs(r["omega_m"] - want).max()
    assert err < bound * scale, f"B = {B}: max |omega_m - eq.(17)| = {err} ({err / scale:.2e} of {scale}), bound {bound}"


# --- directional derivatives: FMU2Model / FMU2Slave ---------------------------------------------


class Instance:
    """An initialized FMU2Model (in continuous-time mode) or FMU2Slave, with its error messages."""

    def __init__(self, path, kind, parameters=None, start=None):
        self.md = fmpy.read_model_description(path)
        self.unzipdir = fmpy.extract(path)
        self.var = {v.name: v for v in self.md.modelVariables}
        self.messages = []
        self._route = LogRoute(lambda _instance, status, category, text: self.messages.append((status, category, text)))
        me = kind == "ME"
        cls, interface = (FMU2Model, self.md.modelExchange) if me else (FMU2Slave, self.md.coSimulation)
        self.fmu = cls(guid=self.md.guid, unzipDirectory=self.unzipdir, modelIdentifier=interface.modelIdentifier,
                       instanceName=kind)
        self.fmu.instantiate(callbacks=self._route.callbacks)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in {**(parameters or {}), **(start or {})}.items():
            v, vr = self.var[name], [self.var[name].valueReference]
            {"Real": self.fmu.setReal, "Boolean": self.fmu.setBoolean}.get(v.type, self.fmu.setInteger)(vr, [value])
        self.fmu.exitInitializationMode()
        self.inputs = [v for v in self.md.modelVariables if v.causality == "input" and v.type == "Real"]
        self.outputs = [u.variable for u in self.md.outputs if u.variable.type == "Real"]
        if me:
            self.fmu.enterContinuousTimeMode()
            self.ders = [u.variable for u in self.md.derivatives]
            self.states = [d.derivative for d in self.ders]
            self.knowns = self.states + self.inputs
            self.unknowns = self.ders + self.outputs
        else:
            self.states, self.ders = [], []
            self.knowns, self.unknowns = self.inputs, self.outputs
        self.nx = len(self.states)

    def set_states(self, x):
        self.fmu.setContinuousStates((ctypes.c_double * self.nx)(*x), self.nx)

    def derivatives(self):
        dx = (ctypes.c_double * self.nx)()
        self.fmu.getDerivatives(dx, self.nx)
        return np.array(dx)

    def evaluate(self, z):
        """Unknowns (derivatives, then outputs) at knowns z (states, then inputs)."""
        if self.nx:
            self.set_states(z[: self.nx])
        self.fmu.setReal([v.valueReference for v in self.inputs], list(z[self.nx:]))
        y = self.fmu.getReal([v.valueReference for v in self.outputs])
        return np.concatenate([self.derivatives() if self.nx else [], y])

    def jacobian(self):
        """Column j: getDirectionalDerivative(all unknowns, [known j], [1])."""
        uvr = [v.valueReference for v in self.unknowns]
        return np.column_stack([self.fmu.getDirectionalDerivative(uvr, [k.valueReference], [1.0]) for k in self.knowns])

    def central_differences(self, z):
        cols = []
        for j in range(len(z)):
            h = 1e-6 * max(1.0, abs(z[j]))
            zp, zm = z.copy(), z.copy()
            zp[j] += h
            zm[j] -= h
            cols.append((self.evaluate(zp) - self.evaluate(zm)) / (2 * h))
        self.evaluate(z)
        return np.column_stack(cols)

    def close(self):
        self.fmu.freeInstance()
        self._route.close()
        shutil.rmtree(self.unzipdir, ignore_errors=True)


# (FMU, parameters, scale of the random states and inputs). The Controller's voltages are
# R/km (M + B omega) + kb omega = 494 (M + 9.09 omega): up to 5.8e4 V per rad with the PID, so its
# points stay within 5e-5 (|U| < 3 V of the 6 V limit); its torques are far from M_max = 20.
JACOBIAN_CASES = {
    "Pendulum": ("Pendulum", {}, 0.5),
    "DCMotor-coupled": ("DCMotor", {"coupled": True}, 0.5),
    "DCMotor-unloaded": ("DCMotor", {"coupled": False}, 0.5),
    "Controller-LQR": ("Controller", {"mode": 1}, 5e-5),
    "Controller-PID": ("Controller", {"mode": 2}, 5e-5),
    "Controller-LQR_PID-motors": ("Controller", {"mode": 3, "drives_motors": True}, 5e-5),
}
POINTS = 5


@contextlib.contextmanager
def points(case, kind):
    """POINTS initialized instances of a case, each at a seeded random point: an iterator of
    (instance, z), each instance freed when the next is made or the block ends."""
    gen = _points(case, kind)
    try:
        yield gen
    finally:
        gen.close()


def _points(case, kind):
    name, params, scale = JACOBIAN_CASES[case]
    for seed in range(POINTS):
        rng = np.random.default_rng(seed)
        if kind == "ME":
            inst = Instance(fmu(name), "ME", params)
            z = rng.uniform(-scale, scale, len(inst.knowns))
        else:
            # Random start states (initial="exact" outputs/locals, and the initial-state parameters
            # <output>_0 of the Pendulum), random inputs, three steps.
            md = fmpy.read_model_description(fmu(name))
            outputs = {v.name for v in md.modelVariables if v.causality == "output"}
            exact = [v.name for v in md.modelVariables if v.type == "Real" and (
                (v.initial == "exact" and v.causality in ("output", "local"))
                or (v.causality == "parameter" and v.name.endswith("_0") and v.name[:-2] in outputs))]
            inst = Instance(fmu(name), "CS", params, start={n: rng.uniform(-scale, scale) for n in exact})
            z = rng.uniform(-scale, scale, len(inst.knowns))
            inst.evaluate(z)
            for k in range(3):
                inst.fmu.doStep(currentCommunicationPoint=k * 1e-3, communicationStepSize=1e-3)
        try:
            inst.evaluate(z)
            if name == "Controller":
                m, u = (inst.fmu.getReal([inst.var[n].valueReference for n in pair]) for pair in (("M1", "M2"), ("U1", "U2")))
                assert max(map(abs, m)) < 10 and max(map(abs, u)) < 4, f"{case} {kind}: test point saturates: M {m}, U {u}"
            yield inst, z
        finally:
            inst.close()


# Measured max |DD - FD| / (1 + |DD|) over the 5 points: Pendulum ME 1.7e-9; DCMotor ME coupled
# 8.3e-9, unloaded 2.8e-8 (rows of 1e5 /s: round-off of eps |f| / h); DCMotor CS 2.4e-11;
# Controller ME and CS 6e-13 (linear there); Pendulum CS 0 (its outputs are states: no input
# reaches them within a step, J = 0 exactly). Bound 3e-7: 10x the worst.
FD_TOL = 3e-7


@pytest.mark.parametrize("kind", ["ME", "CS"])
@pytest.mark.parametrize("case", list(JACOBIAN_CASES))
def test_directional_derivatives_equal_central_differences(case, kind):
    with points(case, kind) as each:
        for seed, (inst, z) in enumerate(each):
            check_jacobian(case, kind, seed, inst, z)


def check_jacobian(case, kind, seed, inst, z):
    jac, fd = inst.jacobian(), inst.central_differences(z)
    dev = np.abs(jac - fd) / (1.0 + np.abs(jac))
    i, j = np.unravel_index(np.argmax(dev), dev.shape)
    assert dev[i, j] <= FD_TOL, (
        f"{case} {kind} point {seed}: d {inst.unknowns[i].name} / d {inst.knowns[j].name} = {jac[i, j]!r}, "
        f"central differences {fd[i, j]!r} (relative {dev[i, j]:.2e} > {FD_TOL})")
    # A seed vector over all knowns at once is the Jacobian times it.
    dv = np.random.default_rng(100 + seed).uniform(-1, 1, len(inst.knowns))
    combined = inst.fmu.getDirectionalDerivative([v.valueReference for v in inst.unknowns],
                                                 [k.valueReference for k in inst.knowns], list(dv))
    want = jac @ dv
    assert np.allclose(combined, want, rtol=1e-12, atol=1e-12 * np.abs(jac).sum(axis=1).max()), (
        f"{case} {kind} point {seed}: directional derivative along {dv} is {combined}, J dv = {want}")


@pytest.mark.parametrize("kind", ["ME", "CS"])
@pytest.mark.parametrize("case", list(JACOBIAN_CASES))
def test_model_structure_zeros_are_exact_zeros(case, kind):
    md = fmpy.read_model_description(fmu(JACOBIAN_CASES[case][0]))
    declared = {u.variable.name: u.dependencies for u in md.outputs + md.derivatives}
    with points(case, kind) as each:
        for seed, (inst, _) in enumerate(each):
            check_structural_zeros(case, kind, seed, inst, declared)


def check_structural_zeros(case, kind, seed, inst, declared):
    jac = inst.jacobian()
    wrong = []
    for i, unknown in enumerate(inst.unknowns):
        deps = declared[unknown.name]
        if deps is None:  # no dependencies attribute: depends on everything
            continue
        names = {d.name for d in deps}
        wrong += [f"d {unknown.name} / d {k.name} = {jac[i, j]!r}" for j, k in enumerate(inst.knowns)
                  if k.name not in names and jac[i, j] != 0.0]
    assert not wrong, f"{case} {kind} point {seed}: not 0 although ModelStructure lists no dependency: {wrong}"


def bad_calls(inst):
    """(what, unknowns, knowns) that fmi2GetDirectionalDerivative must refuse."""
    param = next(v for v in inst.md.modelVariables if v.causality == "parameter" and v.type == "Real")
    out, inp = inst.unknowns[0].valueReference, inst.inputs[0].valueReference
    calls = [(f"parameter {param.name} as known", [out], [param.valueReference]),
             (f"parameter {param.name} as unknown", [param.valueReference], [inp]),
             ("unknown value reference 9999 as unknown", [9999], [inp]),
             ("unknown value reference 9999 as known", [out], [9999])]
    if inst.ders:
        calls.append((f"derivative {inst.ders[0].name} as known", [out], [inst.ders[0].valueReference]))
    return calls


@pytest.mark.parametrize("kind", ["ME", "CS"])
@pytest.mark.parametrize("name", ["Pendulum", "Controller", "DCMotor"])
def test_refused_directional_derivative_raises_and_leaves_the_instance_usable(name, kind):
    case = {"Pendulum": "Pendulum", "Controller": "Controller-LQR_PID-motors", "DCMotor": "DCMotor-unloaded"}[name]
    with points(case, kind) as each:
        inst, z = next(each)
        before = inst.jacobian()
        y_before = inst.evaluate(z)
        for what, unknowns, knowns in bad_calls(inst):
            n = len(inst.messages)
            with pytest.raises(FMICallException):
                inst.fmu.getDirectionalDerivative(unknowns, knowns, [1.0])
            assert any(s == 3 for s, _, _ in inst.messages[n:]), f"{name} {kind}, {what}: no error logged"
            after = inst.jacobian()
            assert np.array_equal(after, before), f"{name} {kind}: after refusing {what}, J = {after}, was {before}"
        assert np.array_equal(inst.evaluate(z), y_before), f"{name} {kind}: values changed by the refused calls"
        if kind == "CS":
            inst.fmu.doStep(currentCommunicationPoint=3e-3, communicationStepSize=1e-3)
        else:
            inst.fmu.setTime(1e-3)
        assert np.isfinite(inst.jacobian()).all()


# --- examples/linearize.py ----------------------------------------------------------------------

G = 9.81
# Eq. (12) in closed form: at rest the mass matrix is [[1/3, 1/6], [1/6, 1/6]] (m = 0.5 kg, l = 1 m),
# its inverse [[6, -6], [-6, 12]] = B's rows, gravity stiffness diag(3/4 g, 1/4 g).
EXACT_A = np.array([[0, 1, 0, 0], [4.5 * G, 0, -1.5 * G, 0], [0, 0, 0, 1], [-4.5 * G, 0, 3 * G, 0]], dtype=float)
EXACT_B = np.array([[0, 0], [6, -6], [0, 0], [-6, 12]], dtype=float)


def test_linearize_gets_eq12_poles_and_eq14_through_directional_derivatives():
    a, b = linearize.linearize(fmu("Pendulum"))
    assert np.abs(a - EXACT_A).max() <= 1e-12, f"A from fmi2GetDirectionalDerivative:\n{a}\nexact:\n{EXACT_A}"
    assert np.abs(b - EXACT_B).max() <= 1e-12, f"B from fmi2GetDirectionalDerivative:\n{b}\nexact:\n{EXACT_B}"
    poles = linearize.open_loop_poles(a)
    assert np.abs(poles.imag).max() == 0.0, poles
    assert np.array_equal(np.round(poles.real, 4), [-7.9571, -3.2031, 3.2031, 7.9571]), f"poles {poles}"
    k = linearize.lqr_gain(a, b)
    paper_k = np.array([[14.0666, 2.8816, 1.1348, 1.0010], [-3.1814, 0.1161, 4.8456, 0.9957]])
    assert np.abs(np.round(k, 4) - paper_k).max() < 1e-12, f"K = {k}, paper (14): {paper_k}"
    assert linearize.problems(a, b, poles, k) == []


def test_linearize_reports_a_number_off_from_the_paper():
    a, b = linearize.linearize(fmu("Pendulum"))
    k = linearize.lqr_gain(a, b) * np.array([[1, 1, 1, 1], [1, 1, 1 + 3e-4, 1]])
    found = linearize.problems(a, b, linearize.open_loop_poles(a), k)
    assert len(found) == 1 and found[0].startswith("K23"), found


def test_linearize_script_exits_0_and_ends_with_a_summary():
    r = subprocess.run([sys.executable, str(ROOT / "examples/linearize.py"), fmu("Pendulum")],
                       capture_output=True, text=True)
    assert r.returncode == 0, f"linearize.py failed ({r.returncode}):\n{r.stdout}\n{r.stderr}"
    last = r.stdout.strip().splitlines()[-1]
    assert last.startswith("OK:") and "7.9571" in last and "3.2031" in last, r.stdout
    assert "14.066567" in r.stdout and "0.116086" in r.stdout, r.stdout
