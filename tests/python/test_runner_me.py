"""Model-exchange components in the native runner (issue 26): an FMI 2.0 FMU without
co-simulation, or one the SSD marks `implementation="ModelExchange"`, is integrated by the runner
(runner/src/me.rs: Dormand-Prince 5(4), time, state and step events through fmi2EnterEventMode /
fmi2NewDiscreteStates). Against the same FMUs' own co-simulation (the runtime's DOPRI5)."""

import re
import zipfile

import numpy as np
import pytest
from conftest import FMU_DIR
from test_runner import rewritten_ssp, rewritten_zip, ssp

import rustfmu_runner


def as_model_exchange(name, component, tmp_path) -> str:
    def mark(ssd):
        text, n = re.subn(rf'(<ssd:Component name="{component}" )', r'\1implementation="ModelExchange" ', ssd)
        assert n == 1
        return text

    return rewritten_ssp(tmp_path, name, mark, f"{name}-{component}-me.ssp")


@pytest.mark.parametrize("name", ["PendulumLQR", "PendulumMotors"])
def test_the_pendulum_integrated_by_the_runner_equals_its_co_simulation(name, tmp_path):
    """The same method (DOPRI5) at the same tolerance on a smooth plant: equal to 1e-12."""
    a = rustfmu_runner.System(ssp(name))
    b = rustfmu_runner.System(as_model_exchange(name, "pendulum", tmp_path))
    ra, rb = a.run(2.0, 1e-3), b.run(2.0, 1e-3)
    for k in ra:
        scale = max(1.0, np.max(np.abs(ra[k])))
        assert np.max(np.abs(ra[k] - rb[k])) <= 1e-12 * scale, k
    assert abs(rb["pendulum.alpha1"][-1]) < 0.05


BALL_SSD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0" name="Ball">
  <ssd:System name="Ball"><ssd:Elements>
    <ssd:Component name="ball" source="resources/BouncingBall.fmu" type="application/x-fmu-sharedlibrary" IMPL/>
  </ssd:Elements></ssd:System>
</ssd:SystemStructureDescription>"""


def ball(tmp_path, impl="", fmu_bytes=None) -> str:
    out = tmp_path / f"ball{len(impl)}{'x' if fmu_bytes else ''}.ssp"
    with zipfile.ZipFile(out, "w") as z:
        z.writestr("SystemStructure.ssd", BALL_SSD.replace("IMPL", impl))
        z.writestr("resources/BouncingBall.fmu", fmu_bytes or (FMU_DIR / "BouncingBall.fmu").read_bytes())
    return str(out)


def without(fmu: bytes, element: bytes) -> bytes:
    """The FMU archive `fmu` with the (empty) element `element` taken out of its modelDescription.xml."""
    import io

    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(fmu)) as f, zipfile.ZipFile(out, "w") as g:
        for i in f.infolist():
            d = f.read(i.filename)
            if i.filename == "modelDescription.xml":
                d, n = re.subn(rb"<" + element + rb"[^>]*/>", b"", d)
                assert n == 1
            g.writestr(i, d)
    return out.getvalue()


def without_co_simulation() -> bytes:
    """BouncingBall.fmu whose modelDescription.xml offers model exchange only."""
    return without((FMU_DIR / "BouncingBall.fmu").read_bytes(), b"CoSimulation")


def test_state_events_of_a_model_exchange_fmu_are_located_and_handled(tmp_path):
    """The bouncing ball: each impact a state event (h crosses 0), located by bisection to 1e-12
    in time and handled in event mode (v reversed and damped): equal to the FMU's own
    co-simulation to 1e-9; the first impact where the free fall says, at sqrt(2 h0 / g)."""
    cs = rustfmu_runner.System(ball(tmp_path))
    me = rustfmu_runner.System(ball(tmp_path, 'implementation="ModelExchange"'))
    ra, rb = cs.run(3.0, 1e-2), me.run(3.0, 1e-2)
    for k in ["ball.h", "ball.v"]:
        assert np.max(np.abs(ra[k] - rb[k])) <= 1e-9, k
    t, v = rb["time"], rb["ball.v"]
    first = np.argmax(v > 0)  # the first point after the first impact
    assert t[first - 1] < np.sqrt(2 * 1.0 / 9.81) <= t[first]
    assert np.sum(np.diff(np.sign(v)) > 0) >= 3  # it bounced, more than once


def test_an_fmu_without_co_simulation_is_integrated_by_the_runner(tmp_path):
    me_only = rustfmu_runner.System(ball(tmp_path, fmu_bytes=without_co_simulation()))
    me = rustfmu_runner.System(ball(tmp_path, 'implementation="ModelExchange"'))
    ra, rb = me_only.run(2.0, 1e-2), me.run(2.0, 1e-2)
    for k in ["ball.h", "ball.v"]:
        assert np.array_equal(ra[k], rb[k]), k


def test_rollback_restores_the_runners_integrator_with_the_fmu_state(tmp_path):
    """Error-controlled steps held at 2 ms over a model-exchange Pendulum: the whole step set
    back (the FMU's state and the integrator's time and step size), the halves equal fixed 1 ms
    steps to 1e-14."""
    s = rustfmu_runner.System(as_model_exchange("PendulumLQR", "pendulum", tmp_path))
    rec = ["pendulum.alpha1", "controller.M1"]
    a = s.run(1.0, 2e-3, record=rec, tolerance=1e9, min_step=2e-3, max_step=2e-3)
    b = s.run(1.0, 1e-3, record=rec)
    for x in rec:
        scale = max(1.0, np.max(np.abs(b[x])))
        assert np.max(np.abs(a[x] - b[x][::2])) <= 1e-14 * scale, x


def fmi3_pendulum_lqr_as_model_exchange(tmp_path, strip_me=False) -> str:
    """target/fmu/fmi3/PendulumLQR.ssp with its (FMI 3.0) Pendulum marked implementation="ModelExchange";
    `strip_me`: and its modelDescription.xml without <ModelExchange>."""

    def edit(member, data):
        if member == "SystemStructure.ssd":
            return data.replace(b'<ssd:Component name="pendulum" ', b'<ssd:Component name="pendulum" implementation="ModelExchange" ')
        if member.endswith("Pendulum.fmu") and strip_me:
            return without(data, b"ModelExchange")
        return data

    return rewritten_zip(FMU_DIR / "fmi3" / "PendulumLQR.ssp", tmp_path / f"fmi3-me{int(strip_me)}.ssp", edit)


def test_an_fmi3_model_exchange_component_equals_its_co_simulation(tmp_path):
    """The FMI 3.0 Pendulum integrated by the runner (fmi3InstantiateModelExchange,
    fmi3GetContinuousStateDerivatives, fmi3UpdateDiscreteStates, ...): equal to its own
    co-simulation to 1e-12, and to the FMI 2.0 Pendulum integrated by the runner bit for bit."""
    a = rustfmu_runner.System(str(FMU_DIR / "fmi3" / "PendulumLQR.ssp")).run(2.0, 1e-3)
    b = rustfmu_runner.System(fmi3_pendulum_lqr_as_model_exchange(tmp_path)).run(2.0, 1e-3)
    c = rustfmu_runner.System(as_model_exchange("PendulumLQR", "pendulum", tmp_path)).run(2.0, 1e-3)
    for k in a:
        scale = max(1.0, np.max(np.abs(a[k])))
        assert np.max(np.abs(a[k] - b[k])) <= 1e-12 * scale, k
        assert np.array_equal(b[k], c[k]), k


def test_an_fmi3_model_exchange_only_fmu_bounces_as_the_fmi2_one(tmp_path):
    """FMI 3.0 BouncingBall.fmu without <CoSimulation>: state events located and handled through
    FMI 3.0's event mode, equal to the FMI 2.0 ball integrated by the runner."""
    me_only = without((FMU_DIR / "fmi3" / "BouncingBall.fmu").read_bytes(), b"CoSimulation")
    v3 = rustfmu_runner.System(ball(tmp_path, fmu_bytes=me_only)).run(3.0, 1e-2)
    v2 = rustfmu_runner.System(ball(tmp_path, fmu_bytes=without_co_simulation())).run(3.0, 1e-2)
    for k in ["ball.h", "ball.v"]:
        assert np.max(np.abs(v3[k] - v2[k])) <= 1e-12, k
    assert np.sum(np.diff(np.sign(v3["ball.v"])) > 0) >= 3


def test_model_exchange_the_runner_cannot_integrate_is_refused(tmp_path):
    with pytest.raises(rustfmu_runner.RunnerError, match="no <ModelExchange> in its modelDescription.xml"):
        rustfmu_runner.System(fmi3_pendulum_lqr_as_model_exchange(tmp_path, strip_me=True))
