"""The paper's closed loops as four FMU instances in real importers: an fmpy FMU2Slave master,
fmpy's SSP runner and libcosim. The FMUs are used only as an importer would."""

import pathlib
import sys

import numpy as np
import pytest
from conftest import FMU_DIR, fmu

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples"))

from cosim import (  # noqa: E402
    closed_loop_matrices,
    linear_response,
    plant_and_controller,
    plant_motors_controller,
    simulate,
)
from cosim.ssp import simulate_fmpy_ssp, simulate_libcosim, ssp_connections, ssp_start_values  # noqa: E402

ANGLES = ["pendulum.alpha1", "pendulum.alpha2"]
K_NAMES = [f"K{i}{j}" for i in (1, 2) for j in (1, 2, 3, 4)]


def ssp(name: str) -> str:
    path = FMU_DIR / f"{name}.ssp"
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo run --release -p fmu-build` (it writes the SSP files)")
    return str(path)


def lqr_system(**kw):
    return plant_and_controller(fmu("Pendulum"), fmu("Controller"), **kw)


def motor_system(**kw):
    return plant_motors_controller(fmu("Pendulum"), fmu("Controller"), fmu("DCMotor"), **kw)


@pytest.fixture(scope="module")
def lqr_run():
    return simulate(lqr_system(), 5.0, 1e-3, {"pendulum": ["alpha1", "alpha2"], "controller": ["M1", "M2"] + K_NAMES})


@pytest.fixture(scope="module")
def motor_run():
    return simulate(
        motor_system(),
        8.0,
        1e-3,
        {"pendulum": ["alpha1", "alpha2"], "controller": ["U1", "U2"], "motor1": ["tau"], "motor2": ["tau"]},
    )


def test_controller_fmu_computes_paper_eq14_gain(lqr_run):
    k = np.array([lqr_run[f"controller.{n}"][-1] for n in K_NAMES]).reshape(2, 4)
    paper = np.array([[14.0666, 2.8816, 1.1348, 1.0010], [-3.1814, 0.1161, 4.8456, 0.9957]])
    assert np.array_equal(np.round(k, 4), paper), f"expected K = {paper}, the FMU computed {k}"


def test_lqr_loop_settles_upright(lqr_run):
    t = lqr_run["time"]
    for name in ANGLES:
        a = lqr_run[name]
        late = np.abs(a[t >= 3.0]).max()
        assert late < 2e-4, f"{name}: |angle| after 3 s should be < 2e-4 rad, was up to {late}"
        assert abs(a[-1]) < 1e-6, f"{name}: at 5 s expected upright within 1e-6 rad, got {a[-1]}"


def test_lqr_loop_converges_to_linear_closed_loop_as_step_shrinks():
    """Near the equilibrium the nonlinear plant is its linearization (12); the master evaluates
    the controller at the state of the same point, so only the zero-order hold remains and the
    co-simulation must approach
    x(t) = exp((A - BK) t) x0 at first order in the communication step."""
    x0 = np.array([1e-3, 0.0, -5e-4, 0.0])
    errors = []
    steps = [8e-3, 4e-3, 2e-3, 1e-3]
    for h in steps:
        r = simulate(
            lqr_system(alpha1=x0[0], alpha2=x0[2]), 2.0, h, {"pendulum": ["alpha1", "alpha2"], "controller": K_NAMES}
        )
        k = np.array([r[f"controller.{n}"][-1] for n in K_NAMES]).reshape(2, 4)
        _, _, acl = closed_loop_matrices(k)
        lin = linear_response(acl, x0, r["time"])
        err = max(np.abs(r["pendulum.alpha1"] - lin[:, 0]).max(), np.abs(r["pendulum.alpha2"] - lin[:, 2]).max())
        errors.append(err / np.abs(x0).max())
    ratios = [errors[i] / errors[i + 1] for i in range(len(errors) - 1)]
    assert all(1.7 < q < 2.3 for q in ratios), f"halving h should halve the error (first order): errors {errors}"
    assert errors[-1] < 0.01, f"at h = 1 ms the relative error should be < 1%, was {errors[-1]}"


def test_linear_reference_is_paper_eq15():
    """The Python reference A - BK has the closed-loop polynomial of equation (15)."""
    k = np.array([[14.0666, 2.8816, 1.1348, 1.0010], [-3.1814, 0.1161, 4.8456, 0.9957]])
    _, _, acl = closed_loop_matrices(k)
    np.testing.assert_allclose(np.poly(acl), [1, 22.536, 180.364, 598.656, 707.968], rtol=5e-4)


def test_motor_loop_settles_upright_within_voltage_limits(motor_run):
    t = motor_run["time"]
    for u in ("controller.U1", "controller.U2"):
        assert np.abs(motor_run[u]).max() <= 6.0 + 1e-12, f"{u} exceeded the 6 V supply"
    assert np.abs(motor_run["controller.U1"]).max() == pytest.approx(6.0), "the demo should hit the voltage limit"
    for name in ANGLES:
        a = motor_run[name]
        early, late = np.abs(a[(t >= 1) & (t < 2)]).max(), np.abs(a[t >= 7]).max()
        assert late < 1e-3, f"{name}: |angle| after 7 s should be < 1e-3 rad, was up to {late}"
        assert late < early / 3, f"{name}: the deviation should shrink by 3x, 1-2 s: {early}, 7-8 s: {late}"


@pytest.mark.parametrize("name", ["PendulumLQR", "PendulumMotors"])
def test_master_loop_reads_the_same_system_from_the_ssp_as_fmpy(name):
    """The master loop's systems come from the SSP files (cosim.systems reads the SSD with
    xml.etree); fmpy's own SSD reader must find the same connections and typed start values."""
    system = lqr_system() if name == "PendulumLQR" else motor_system()
    expected = {(k.source, k.source_var, k.target, k.target_var) for k in system.connections}
    got = ssp_connections(ssp(name))
    assert got == expected, f"{name}.ssp connections differ: only in fmpy's reading {got - expected}, only in master {expected - got}"
    starts = {f"{c.name}.{k}": v for c in system.components for k, v in c.start.items()}
    fmpy_starts = {p.name: p.value for p in ssp_start_values(ssp(name)).parameters}
    assert starts == fmpy_starts, f"{name}.ssp start values: master loop reads {starts}, fmpy reads {fmpy_starts}"
    assert all(type(v) is type(fmpy_starts[k]) for k, v in starts.items()), f"{name}: types differ: {starts} vs {fmpy_starts}"


@pytest.fixture(scope="module")
def motor_run_default_mode():
    """The motor loop with the Controller's mode at its default (LQR): what libcosim runs, since
    it ignores FMI 2.0 Enumeration variables ("variable with name mode will be ignored") and so
    cannot apply the SSP file's mode = LQR_PID."""
    return simulate(motor_system(mode=1), 5.0, 1e-3, {"pendulum": ["alpha1", "alpha2"]}, order="jacobi")


@pytest.mark.parametrize("name", ["PendulumLQR", "PendulumMotors"])
def test_fmpy_ssp_and_libcosim_agree_with_master_loop(name, motor_run_default_mode):
    """fmpy.ssp and libcosim's fixed-step algorithm are Jacobi masters (every output read before
    any input is set), so they are compared with the master loop run in that order."""
    path = ssp(name)
    system = lqr_system() if name == "PendulumLQR" else motor_system()
    master = simulate(system, 5.0, 1e-3, {"pendulum": ["alpha1", "alpha2"]}, order="jacobi")
    as_libcosim_runs_it = master if name == "PendulumLQR" else motor_run_default_mode
    a = simulate_fmpy_ssp(path, 5.0, 1e-3, ANGLES)
    b = simulate_libcosim(path, 5.0, 1e-3, ANGLES, {})
    for v in ANGLES:
        # libcosim propagates the connections in initialization mode, as the master does: same
        # sequence of calls, so the same numbers up to round-off.
        ref = as_libcosim_runs_it
        diff_cosim = np.abs(b[v] - np.interp(b["time"], ref["time"], ref[v])).max()
        assert diff_cosim < 1e-9, f"{name} {v}: libcosim differs from the fmpy master by {diff_cosim} rad"
        # fmpy's SSP runner starts every connector at 0 (no propagation at initialization), so
        # the controller sees the true state one step late at the start: an O(h) difference.
        diff_fmpy = np.abs(a[v] - np.interp(a["time"], master["time"], master[v])).max()
        assert diff_fmpy < 2e-3, f"{name} {v}: fmpy.ssp differs from the fmpy master by {diff_fmpy} rad"
