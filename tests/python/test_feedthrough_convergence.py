"""The Controller's feedthrough, measured with a small master of its own (fmpy's FMU2Slave, no
project code): at every communication point the plant's state is set on the Controller and its
torques are read at once and set on the plant, then both step. Near the upright position the
loop must approach the linear closed loop A - BK of eqs. (12) and (14) with the error of the
zero-order hold only; with sampled = true, with the zero-order hold and one step of delay.
With the plant's exact output derivatives (fmi2GetRealOutputDerivatives, issue 26) the master
gives the Controller the state extrapolated to the middle of the step, x + h/2 dx/dt, so the held
torque is the step's mean to second order: the error of the coupling falls with h^2. With the
Pendulum's input derivatives too (canInterpolateInputs, fmi2SetRealInputDerivatives) the master
gives the plant a first-order hold instead: the torques and their rate dM/dt = dM/dx dx/dt (the
Controller's exact directional derivative along the plant's exact output derivatives), over
which the plant's integrator ramps the torques through the step: second order as well.

The measure (docs/composition.md, "Convergence"): the largest deviation of any of the four states
from x(t) = expm((A - BK) t) x0 over 2 s, as a fraction of the initial deviation max|x0|, from
x0 = (1e-3, 0, -5e-4, 0).
"""

import numpy as np
import pytest
import scipy.linalg
from conftest import fmu
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

# The paper's printed eq. (12) and (14).
A = np.array([[0.0, 1.0, 0.0, 0.0], [44.145, 0.0, -14.715, 0.0], [0.0, 0.0, 0.0, 1.0], [-44.145, 0.0, 29.43, 0.0]])
B = np.array([[0.0, 0.0], [6.0, -6.0], [0.0, 0.0], [-6.0, 12.0]])
K = np.array([[14.0666, 2.8816, 1.1348, 1.0010], [-3.1814, 0.1161, 4.8456, 0.9957]])
X0 = np.array([1e-3, 0.0, -5e-4, 0.0])
STATE = ["alpha1", "omega1", "alpha2", "omega2"]


class Slave:
    def __init__(self, name):
        path = fmu(name)
        self.md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.s = FMU2Slave(guid=self.md.guid, unzipDirectory=extract(path),
                           modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.s.instantiate()

    def set(self, names, values):
        self.s.setReal([self.vr[n] for n in names], list(values))

    def get(self, names):
        return np.array(self.s.getReal([self.vr[n] for n in names]))


def deviation(h, sampled=None, stop=2.0, midpoint=False, ramp=False):
    """max over the communication points of max_i |x_i - x_lin,i| / max|x0|. `midpoint`: the
    Controller is given x + h/2 dx/dt, dx/dt the plant's output derivatives at the point (with
    the torques still those of the step before). `ramp`: a first-order hold of the torques, M set
    on the plant with dM/dt = dM/dx dx/dt (fmi2SetRealInputDerivatives), dx/dt the plant's output
    derivatives with those torques, dM/dx the Controller's directional derivative."""
    plant, controller = Slave("Pendulum"), Slave("Controller")
    try:
        # The initial state: initial-state parameters where the Pendulum has them, else the states' start values.
        names = [f"{n}_0" for n in ("alpha1", "alpha2")] if "alpha1_0" in plant.vr else ["alpha1", "alpha2"]
        plant.set(names, [X0[0], X0[2]])
        if sampled is not None:
            controller.s.setBoolean([controller.vr["sampled"]], [sampled])
        n = int(round(stop / h))
        for s in (plant, controller):
            s.s.setupExperiment(startTime=0.0, stopTime=n * h)
            s.s.enterInitializationMode()
        controller.set(STATE, plant.get(STATE))
        plant.set(["M1", "M2"], controller.get(["M1", "M2"]))
        for s in (plant, controller):
            s.s.exitInitializationMode()
        step = scipy.linalg.expm((A - B @ K) * h)
        x_lin, worst = X0.copy(), 0.0
        for k in range(n + 1):
            x = plant.get(STATE)
            worst = max(worst, np.abs(x - x_lin).max())
            if k == n:
                break
            if midpoint:
                rates = plant.s.getRealOutputDerivatives([plant.vr[n] for n in STATE], [1] * len(STATE))
                controller.set(STATE, x + 0.5 * h * np.array(rates))
            else:
                controller.set(STATE, x)
            plant.set(["M1", "M2"], controller.get(["M1", "M2"]))
            if ramp:
                rates = plant.s.getRealOutputDerivatives([plant.vr[n] for n in STATE], [1] * len(STATE))
                torques = [controller.vr[m] for m in ("M1", "M2")]
                dm = controller.s.getDirectionalDerivative(torques, [controller.vr[n] for n in STATE], list(rates))
                plant.s.setRealInputDerivatives([plant.vr["M1"], plant.vr["M2"]], [1, 1], list(dm))
            for s in (plant, controller):
                s.s.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
            x_lin = step @ x_lin
        return worst / np.abs(X0).max()
    finally:
        for s in (plant, controller):
            s.s.terminate()
            s.s.freeInstance()


def linear_discrete(h, delay, stop=2.0):
    """The same measure for the linear plant (12) under the zero-order hold, u_k = -K x_k, or
    with one step of delay u_k = -K x_(k-1): what the co-simulation should give."""
    m = scipy.linalg.expm(np.block([[A, B], [np.zeros((2, 6))]]) * h)
    ad, bd, step = m[:4, :4], m[:4, 4:], scipy.linalg.expm((A - B @ K) * h)
    x, held, x_lin, worst = X0.copy(), X0.copy(), X0.copy(), 0.0
    for _ in range(int(round(stop / h))):
        u = -K @ (held if delay else x)
        held = x
        x, x_lin = ad @ x + bd @ u, step @ x_lin
        worst = max(worst, np.abs(x - x_lin).max())
    return worst / np.abs(X0).max()


def linear_midpoint(h, stop=2.0):
    """The same measure for the linear plant (12) under the zero-order hold of
    u_k = -K (x_k + h/2 (A x_k + B u_(k-1))): what the master with output derivatives should give."""
    m = scipy.linalg.expm(np.block([[A, B], [np.zeros((2, 6))]]) * h)
    ad, bd, step = m[:4, :4], m[:4, 4:], scipy.linalg.expm((A - B @ K) * h)
    x, u, x_lin, worst = X0.copy(), -K @ X0, X0.copy(), 0.0
    for _ in range(int(round(stop / h))):
        u = -K @ (x + 0.5 * h * (A @ x + B @ u))
        x, x_lin = ad @ x + bd @ u, step @ x_lin
        worst = max(worst, np.abs(x - x_lin).max())
    return worst / np.abs(X0).max()


def linear_ramp(h, stop=2.0):
    """The same measure for the linear plant (12) with the first-order hold of the torques,
    u(t_k + s) = u_k + s du_k, u_k = -K x_k, du_k = -K (A x_k + B u_k): what the master with input
    derivatives should give."""
    m = np.zeros((8, 8))
    m[:4, :4], m[:4, 4:6], m[4:6, 6:8] = A, B, np.eye(2)
    phi, step = scipy.linalg.expm(m * h), scipy.linalg.expm((A - B @ K) * h)
    x, x_lin, worst = X0.copy(), X0.copy(), 0.0
    for _ in range(int(round(stop / h))):
        u = -K @ x
        du = -K @ (A @ x + B @ u)
        x, x_lin = phi[:4, :4] @ x + phi[:4, 4:6] @ u + phi[:4, 6:8] @ du, step @ x_lin
        worst = max(worst, np.abs(x - x_lin).max())
    return worst / np.abs(X0).max()


# Measured (this test's master; docs/composition.md): feedthrough 4.16e-2 (2 ms), 1.03e-2 (0.5 ms);
# sampled 1.27e-1, 3.10e-2. The linear discrete loop gives the same to 3 digits.
@pytest.mark.parametrize("h, expected", [(2e-3, 0.042), (5e-4, 0.0103)])
def test_feedthrough_leaves_only_the_zero_order_hold(h, expected):
    err = deviation(h)
    assert err == pytest.approx(expected, rel=0.05), f"h = {h}: largest deviation from A - BK {err:.4g} of x0, expected {expected} (zero-order hold only)"
    assert err == pytest.approx(linear_discrete(h, delay=False), rel=0.02)


@pytest.mark.parametrize("h", [2e-3, 5e-4])
def test_sampled_controller_adds_one_step_of_delay(h):
    err, expected = deviation(h, sampled=True), linear_discrete(h, delay=True)
    assert err == pytest.approx(expected, rel=0.02), f"h = {h}: sampled = true gives {err:.4g} of x0, one step of delay gives {expected:.4g}"
    assert err > 2.5 * deviation(h, sampled=False), "the delay should at least triple the error"


def test_output_derivatives_make_the_coupling_second_order():
    """Issue 26's goal, at most 0.5 % of x0 at h = 2 ms (4.15 % with the zero-order hold alone):
    with the plant's output derivatives the master extrapolates the state to the middle of the
    step. Measured 9.83e-4 at 2 ms, 3.67e-3 at 4 ms (ratio 3.7: second order); the linear loop
    under the same scheme gives 8.99e-4 and 3.59e-3, the remaining 1e-4 being what separates the
    nonlinear plant and the computed K from the printed A - BK (the floor the finer steps reach:
    1.7e-4 at 0.5 ms, 1.4e-4 at 0.25 ms)."""
    two, four = deviation(2e-3, midpoint=True), deviation(4e-3, midpoint=True)
    assert two <= 5e-3 and two < deviation(2e-3) / 20, f"h = 2 ms: {two:.3g} of x0 with output derivatives"
    assert four / two > 3.0, f"4 ms -> 2 ms: {four:.3g} -> {two:.3g}, not second order"
    for h, err in ((2e-3, two), (4e-3, four)):
        assert abs(err - linear_midpoint(h)) < 1.5e-4, f"h = {h}: {err:.4g}, the linear loop {linear_midpoint(h):.4g}"


def test_input_derivatives_give_the_plant_a_first_order_hold():
    """Issue 26: the Pendulum follows the torques' derivatives over the step (canInterpolateInputs);
    the master ramps the torques with dM/dt from the Controller's directional derivative along
    the plant's output derivatives. Second order, as the linear loop under the same hold: measured
    4.46e-3 (8 ms), 1.14e-3 (4 ms), 3.54e-4 (2 ms; the midpoint scheme 9.83e-4, the zero-order hold
    4.15e-2), 1.43e-4 (0.5 ms), down to the same floor of ~1.35e-4 (the nonlinear plant and the
    computed K against the printed A - BK); the linear loop 4.37e-3, 1.05e-3, 2.56e-4, 1.6e-5."""
    two, four = deviation(2e-3, ramp=True), deviation(4e-3, ramp=True)
    assert two <= 5e-3 and two < deviation(2e-3) / 20, f"h = 2 ms: {two:.3g} of x0 with input derivatives"
    assert four / two > 2.9, f"4 ms -> 2 ms: {four:.3g} -> {two:.3g}, not second order"
    for h, err in ((2e-3, two), (4e-3, four)):
        assert abs(err - linear_ramp(h)) < 1.5e-4, f"h = {h}: {err:.4g}, the linear loop {linear_ramp(h):.4g}"
