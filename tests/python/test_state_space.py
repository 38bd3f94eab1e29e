"""Issue 25: structural parameters, Configuration Mode and arrays in the equations. The
Reference-FMUs' StateSpace written with rustfmu (reference-fmus/state_space, FMI 3.0
only): dx/dt = A x + B u, y = C x + D u, x(0) = x0, with m inputs, n states and r outputs set
in Configuration Mode. Through fmpy's FMU3Slave and FMU3Model: the sizes change in
Configuration Mode (and again in Reconfiguration Mode), the outputs equal an independent
solution (scipy's expm for the exact zero-order-hold answer, and solve_ivp) for two sizes, and
the directional and adjoint derivatives over the array elements are A, B, C, D."""

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Model, FMU3Slave

from conftest import fmu3

VR = dict(m=1, n=2, r=3, A=4, B=5, C=6, D=7, x0=8, u=9, y=10, x=11, der_x=12)


@pytest.fixture(scope="module")
def state_space():
    path = fmu3("StateSpace")
    md = read_model_description(path)
    return md, extract(path)


def make(state_space, cls, m, n, r, A, B, C, D, x0):
    """An instance with sizes (m, n, r) set in Configuration Mode and the matrices, x0 set."""
    md, unzipdir = state_space
    kwargs = dict(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier="StateSpace", instanceName="ss")
    f = cls(**kwargs)
    f.instantiate()
    f.enterConfigurationMode()
    f.setUInt64([VR["m"], VR["n"], VR["r"]], [m, n, r])
    f.exitConfigurationMode()
    assert f.getUInt64([VR["m"], VR["n"], VR["r"]]) == [m, n, r]
    for name, value in dict(A=A, B=B, C=C, D=D, x0=x0).items():
        f.setFloat64([VR[name]], list(np.ravel(value)))
    f.enterInitializationMode(startTime=0.0)
    f.exitInitializationMode()
    return f


SIZES = [
    # (m, n, r): a square system like the Reference-FMUs' default, and one where m != r (theirs
    # sums B u over r columns: wrong here).
    (3, 3, 3),
    (2, 4, 1),
]


def system(m, n, r, seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n)) - 2.0 * np.eye(n)  # stable
    B = rng.normal(size=(n, m))
    C = rng.normal(size=(r, n))
    D = rng.normal(size=(r, m))
    x0 = rng.normal(size=n)
    u = rng.normal(size=m)
    return A, B, C, D, x0, u


def exact(A, B, C, D, x0, u, t):
    """y(t) for a constant u: x(t) = e^{At} x0 + (∫_0^t e^{As} ds) B u (the block exponential)."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    E = scipy.linalg.expm(M * t)
    x = E[:n, :n] @ x0 + E[:n, n:] @ u
    return x, C @ x + D @ u


@pytest.mark.parametrize("m,n,r", SIZES)
def test_co_simulation_equals_the_exact_solution(state_space, m, n, r):
    A, B, C, D, x0, u = system(m, n, r, seed=m * 100 + n * 10 + r)
    f = make(state_space, FMU3Slave, m, n, r, A, B, C, D, x0)
    f.setFloat64([VR["u"]], list(u))
    # Start values: x = x0 (the Reference-FMUs' start at 0 whatever x0 is), y = C x0 + D u.
    assert np.allclose(f.getFloat64([VR["x"]], nValues=n), x0, rtol=0, atol=0)
    assert np.allclose(f.getFloat64([VR["y"]], nValues=r), C @ x0 + D @ u, rtol=1e-15, atol=1e-15)
    t, h, worst = 0.0, 0.05, 0.0
    for _ in range(40):
        f.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t += h
        x_ref, y_ref = exact(A, B, C, D, x0, u, t)
        x = np.array(f.getFloat64([VR["x"]], nValues=n))
        y = np.array(f.getFloat64([VR["y"]], nValues=r))
        worst = max(worst, np.max(np.abs(x - x_ref)), np.max(np.abs(y - y_ref)))
    # The runtime's Dopri5 at its default tolerance (1e-6 relative)
    assert worst < 1e-5 * max(1.0, np.max(np.abs(x_ref))), worst
    f.terminate()
    f.freeInstance()


@pytest.mark.parametrize("m,n,r", SIZES)
def test_model_exchange_has_n_states_and_its_integration_equals_solve_ivp(state_space, m, n, r):
    A, B, C, D, x0, u = system(m, n, r, seed=7 + n)
    f = make(state_space, FMU3Model, m, n, r, A, B, C, D, x0)
    f.setFloat64([VR["u"]], list(u))
    assert f.getNumberOfContinuousStates() == n
    f.enterContinuousTimeMode()
    x = np.zeros(n)
    dx = np.zeros(n)
    ptr = lambda a: a.ctypes.data_as(__import__("ctypes").POINTER(__import__("ctypes").c_double))  # noqa: E731
    f.getContinuousStates(ptr(x), n)
    assert np.array_equal(x, x0)

    def rhs(t, xs):
        f.setTime(t)
        f.setContinuousStates(ptr(np.ascontiguousarray(xs)), n)
        f.getContinuousStateDerivatives(ptr(dx), n)
        return dx.copy()

    sol = scipy.integrate.solve_ivp(rhs, (0.0, 2.0), x0, rtol=1e-10, atol=1e-12)
    x_ref, y_ref = exact(A, B, C, D, x0, u, 2.0)
    assert np.allclose(sol.y[:, -1], x_ref, rtol=1e-8, atol=1e-9)
    f.setTime(2.0)
    f.setContinuousStates(ptr(np.ascontiguousarray(sol.y[:, -1])), n)
    y = np.array(f.getFloat64([VR["y"]], nValues=r))
    assert np.allclose(y, y_ref, rtol=1e-8, atol=1e-9)
    f.terminate()
    f.freeInstance()


@pytest.mark.parametrize("m,n,r", SIZES)
def test_directional_and_adjoint_derivatives_over_the_elements_are_A_B_C_D(state_space, m, n, r):
    A, B, C, D, x0, u = system(m, n, r, seed=3)
    f = make(state_space, FMU3Model, m, n, r, A, B, C, D, x0)
    f.enterContinuousTimeMode()
    # The Jacobian of (der(x), y) with respect to (x, u), one column per seed of n + m elements.
    J = np.zeros((n + r, n + m))
    for j in range(n + m):
        seed = np.zeros(n + m)
        seed[j] = 1.0
        J[:, j] = f.getDirectionalDerivative(
            [VR["der_x"], VR["y"]], [VR["x"], VR["u"]], list(seed), nSensitivity=n + r
        )
    assert np.array_equal(J[:n, :n], A)
    assert np.array_equal(J[:n, n:], B)
    assert np.array_equal(J[n:, :n], C)
    assert np.array_equal(J[n:, n:], D)
    # The adjoint: Jᵀ w.
    w = np.arange(1.0, n + r + 1.0)
    adj = f.getAdjointDerivative([VR["der_x"], VR["y"]], [VR["x"], VR["u"]], list(w), nSensitivity=n + m)
    assert np.allclose(adj, J.T @ w, rtol=1e-14, atol=1e-14)
    f.terminate()
    f.freeInstance()


def test_reconfiguration_changes_the_sizes_between_steps(state_space):
    """Step Mode → Reconfiguration Mode: n from 3 to 2; the arrays shrink, the states kept are
    the first two, and stepping goes on with the new A (2 × 2: its top-left corner)."""
    m, n, r = 3, 3, 3
    A, B, C, D, x0, u = system(m, n, r, seed=11)
    f = make(state_space, FMU3Slave, m, n, r, A, B, C, D, x0)
    f.setFloat64([VR["u"]], list(u))
    f.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.1)
    x = np.array(f.getFloat64([VR["x"]], nValues=3))
    f.enterConfigurationMode()
    f.setUInt64([VR["n"]], [2])
    f.exitConfigurationMode()
    assert f.getFloat64([VR["A"]], nValues=4) == list(np.ravel(A[:2, :2]))
    assert f.getFloat64([VR["B"]], nValues=6) == list(np.ravel(B[:2, :]))
    x2 = np.array(f.getFloat64([VR["x"]], nValues=2))
    assert np.array_equal(x2, x[:2])
    f.doStep(currentCommunicationPoint=0.1, communicationStepSize=0.1)
    # From x2 at 0.1 with the 2-state system.
    x_ref, y_ref = exact(A[:2, :2], B[:2, :], C[:, :2], D, x2, u, 0.1)
    assert np.allclose(f.getFloat64([VR["x"]], nValues=2), x_ref, rtol=1e-5, atol=1e-6)
    assert np.allclose(f.getFloat64([VR["y"]], nValues=3), y_ref, rtol=1e-5, atol=1e-6)
    f.terminate()
    f.freeInstance()


def test_sizes_are_set_only_in_configuration_mode_and_within_max(state_space):
    md, unzipdir = state_space
    kwargs = dict(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier="StateSpace", instanceName="ss")
    messages = []

    def log(env, status, category, message):
        messages.append(message.decode())

    f = FMU3Slave(**kwargs)
    f.instantiate(logMessage=log)
    with pytest.raises(Exception):
        f.setUInt64([VR["n"]], [2])
    assert "structural parameters are set in Configuration Mode" in messages[-1]
    f.freeInstance()
    f = FMU3Slave(**kwargs)
    f.instantiate(logMessage=log)
    f.enterConfigurationMode()
    with pytest.raises(Exception):
        f.setUInt64([VR["n"]], [6])
    assert "6 for 'n' (vr 2) is outside" in messages[-1], messages[-1]
    f.freeInstance()
    # The description says the same: m, n, r are structural parameters with max 5, and A is
    # sized by n twice.
    names = {v.name: v for v in md.modelVariables}
    assert names["n"].causality == "structuralParameter"
    # (fmpy 0.3.32 reads no max of a UInt64: from the file itself.)
    import xml.etree.ElementTree as ET

    root = ET.parse(f"{unzipdir}/modelDescription.xml").getroot()
    n = root.find("./ModelVariables/UInt64[@name='n']")
    assert (n.get("causality"), n.get("variability"), n.get("start"), n.get("max")) == (
        "structuralParameter",
        "tunable",
        "3",
        "5",
    )
    assert [d.valueReference for d in names["A"].dimensions] == [VR["n"], VR["n"]]
    assert [d.valueReference for d in names["B"].dimensions] == [VR["n"], VR["m"]]
