"""The joints' extra inertia J1, J2 (geared motor rotors, n^2 J) in the Pendulum and the Controller
FMUs, against an independent solution of the extended equations (paper_model with J1, J2: the
mass matrix of (6)-(7) with J1 on its (1,1) and J2 on its (2,2) entry, solved by numpy, integrated
by scipy's DOP853 at rtol = atol = 1e-12) and an independent LQR design (scipy's Riccati solver).
"""

import fmpy
import numpy as np
import pytest
import scipy.linalg

import paper_model
from conftest import fmu
from fmi_harness import value_after_a_refused_set

STATE = ["alpha1", "omega1", "alpha2", "omega2"]
X0 = (0.1, 0.5, -0.05, -0.3)  # moving: the rotors' kinetic energy is not 0 at the start
STOP = 2.0
ROTOR = 200.0**2 * 2.18e-5  # n^2 J of the full loop's motors: 0.872 kg.m2

# (J1, J2, M1, M2): both rotors with and without torque, and each alone (a J added to the wrong
# diagonal entry, or to both, gives another trajectory). Over 2 s every case leaves upright and
# swings through several radians; the J = 0 solution differs from these by 13.8 to 22.5 rad.
CASES = {
    "both": (ROTOR, ROTOR, 0.0, 0.0),
    "both-torques": (ROTOR, ROTOR, 1.0, -0.5),
    "J1-only": (ROTOR, 0.0, 0.0, 0.0),
    "J2-only": (0.0, 0.3, 0.0, 0.0),
}

# Measured max |x - reference| over the 4 states, 2 s, outputs every 10 ms, over the 4 cases:
# co-simulation (the FMU's Dormand-Prince at its default rtol = atol = 1e-10, step 10 ms)
# 2.0e-11 .. 1.1e-9; model exchange (fmpy's CVode, relative_tolerance 1e-10) 2.5e-8 .. 1.5e-6, the
# largest where the pendulum swings fastest (J2-only). Bounds 10x the largest.
BOUND = {"CoSimulation": 1e-8, "ModelExchange": 1e-5}


def run(kind, j1, j2, m1, m2):
    start = dict(zip([f"{n}_0" for n in STATE], X0), J1=j1, J2=j2)
    inputs = np.array([(0.0, m1, m2)], dtype=[("time", float), ("M1", float), ("M2", float)])
    extra = {"step_size": 1e-2} if kind == "CoSimulation" else {"solver": "CVode", "relative_tolerance": 1e-10}
    return fmpy.simulate_fmu(fmu("Pendulum"), fmi_type=kind, stop_time=STOP, output_interval=1e-2,
                             start_values=start, input=inputs, output=STATE + ["energy"], **extra)


@pytest.mark.parametrize("kind", ["CoSimulation", "ModelExchange"])
@pytest.mark.parametrize("case", list(CASES))
def test_pendulum_with_rotor_inertia_follows_the_extended_equations(case, kind):
    j1, j2, m1, m2 = CASES[case]
    r = run(kind, j1, j2, m1, m2)
    assert r["time"][-1] == pytest.approx(STOP), f"{case}/{kind}: stopped at {r['time'][-1]}"
    got = np.column_stack([r[n] for n in STATE])
    ref = paper_model.reference(X0, r["time"], M1=m1, M2=m2, J1=j1, J2=j2)
    err = np.abs(got - ref).max()
    assert err < BOUND[kind], f"{case}/{kind}: max |x - extended (6)-(7)| = {err:.3e} rad(/s), bound {BOUND[kind]}"
    without = paper_model.reference(X0, r["time"], M1=m1, M2=m2)
    assert np.abs(got - without).max() > 1.0, f"{case}/{kind}: J1 = {j1}, J2 = {j2} made no difference"


@pytest.mark.parametrize("case", ["both", "J1-only", "J2-only"])
def test_energy_with_rotor_inertia_is_the_extended_one_and_constant(case):
    # Measured: the FMU's initial energy equals paper_model.energy with J to the last bit; drift
    # over 2 s in co-simulation 7e-11 .. 2.2e-10 J. Bounds 1e-12 J and 10x.
    j1, j2, _, _ = CASES[case]
    r = run("CoSimulation", j1, j2, 0.0, 0.0)
    want = paper_model.energy(X0, J1=j1, J2=j2)
    rotors = (j1 * X0[1] ** 2 + j2 * X0[3] ** 2) / 2
    assert abs(r["energy"][0] - want) < 1e-12, (
        f"{case}: initial energy {r['energy'][0]!r} J, expected (2)-(5) + J1 w1^2/2 + J2 w2^2/2 = {want!r} "
        f"(the rotors' share is {rotors:.4g} J)"
    )
    drift = np.abs(r["energy"] - r["energy"][0]).max()
    assert drift < 3e-9, f"{case}: energy drifted by {drift:.3e} J over {STOP} s without torque"


def lqr_for(j1, j2, m1=0.5, m2=0.5, l1=1.0, l2=1.0, g=9.81):
    """The paper's design (Q = C'C, R = I) for the plant with rotors, linearized upright by hand."""
    mass = np.array([[(m1 + m2) * l1**2 / 3 + j1, m2 * l1 * l2 / 3], [m2 * l1 * l2 / 3, m2 * l2**2 / 3 + j2]])
    minv = np.linalg.inv(mass)
    acc = minv @ np.diag([m1 * g * l1 / 2 + m2 * g * l1, m2 * g * l2 / 2])
    a = np.zeros((4, 4))
    a[0, 1] = a[2, 3] = 1.0
    a[1, [0, 2]], a[3, [0, 2]] = acc[0], acc[1]
    b = np.zeros((4, 2))
    b[1], b[3] = minv[0], minv[1]
    q = np.diag([1.0, 0.0, 1.0, 0.0])
    p = scipy.linalg.solve_continuous_are(a, b, q, np.eye(2))
    return b.T @ p, a, b


def test_controller_designs_its_lqr_for_the_plant_with_rotors():
    # Measured max |K_FMU - K_scipy| = 2.1e-14 (1.4e-15 of max |K|) at J = 0.872; bound 1e-10
    # relative. K = [14.7600 5.9482 0.2067 0.4500; -0.5796 0.0864 5.0930 3.2321], poles of A - BK
    # -2.521 +- 0.178i, -1.557 +- 0.301i (the paper's plant and K: -7.999 +- 0.929i, -3.269 +- 0.479i).
    names = [f"K{i}{j}" for i in (1, 2) for j in (1, 2, 3, 4)]
    r = fmpy.simulate_fmu(fmu("Controller"), stop_time=1e-3, step_size=1e-3,
                          start_values={"J1": ROTOR, "J2": ROTOR}, output=names)
    k = np.array([r[n][-1] for n in names]).reshape(2, 4)
    want, a, b = lqr_for(ROTOR, ROTOR)
    assert np.abs(k - want).max() < 1e-10 * np.abs(want).max(), f"K = {k}, scipy's LQR for J = 0.872 gives {want}"
    paper, _, _ = lqr_for(0.0, 0.0)
    assert np.abs(k - paper).max() > 1.0, f"K = {k} is still the paper's gain {paper}"
    poles = np.linalg.eigvals(a - b @ k)
    assert poles.real.max() < 0, f"A - BK of the plant with rotors has poles {poles}"


@pytest.mark.parametrize("name", ["Pendulum", "Controller"])
@pytest.mark.parametrize("var,value", [("J1", -1e-3), ("J2", float("nan")), ("J1", float("inf"))])
def test_a_negative_or_non_finite_inertia_is_refused_naming_it(name, var, value):
    assert value_after_a_refused_set(fmu(name), var, value) == 0.0, f"{name}.{var}: the refused value was stored"
