"""Algebraic loops in the native runner (runner/README.md, "Algebraic loops"), through its Python
module and command line: a loop of the project's FMUs, FMI 2.0 and FMI 3.0, and one with the C
Reference-FMUs' FMI 3.0 Feedthrough (no directional derivatives), written here as SSP files and
compared with the same equations solved here with numpy.

The system: two DC motors (DCMotor, coupled: joint speed `omega` in, torque `tau` out with direct
feedthrough), each driving a massless viscous load of 1 N.m.s/rad (a Feedthrough FMU) whose speed
is the other motor's joint speed. At each communication point the loop is

    w_a + B_b w_b = km_b i_b,    B_a w_a + w_b = km_a i_a     (gear ratio 1)

and over a step each current follows L di/dt = U - R i - kb w with its w held."""

import subprocess
import zipfile

import numpy as np
import pytest
import rustfmu_runner
from conftest import FMU_DIR, ROOT, fmu, fmu3

THEIRS = ROOT.parent / "shared" / "independent" / "reference-fmus" / "3.0"
CLI = FMU_DIR.parent / "release" / "rustfmu-runner"
A = dict(L=0.1, R=1.0, km=0.5, kb=0.5, B=2.0, U=1.0, i=0.2)
B = dict(L=0.2, R=2.0, km=0.4, kb=0.3, B=1.5, U=-0.5, i=0.0)
RECORD = ["motor_a.i", "motor_b.i", "motor_a.tau", "motor_b.tau"]


def theirs(name):
    path = THEIRS / f"{name}.fmu"
    if not path.exists():
        pytest.fail(f"{path} is missing (the C Reference-FMUs v0.0.41 of shared/independent)")
    return str(path)


def system(path, dcmotor, feedthrough, a=A, b=B) -> str:
    """The SSP file of the two motors (FMU `dcmotor`) and their loads (FMU `feedthrough`) at `path`."""

    def motor(name, m):
        values = {**m, "gear_ratio": 1.0}
        ps = "".join(f'<ssv:Parameter name="{k}"><ssv:Real value="{v!r}"/></ssv:Parameter>' for k, v in values.items())
        return (
            f'<ssd:Component name="{name}" source="resources/DCMotor.fmu"><ssd:ParameterBindings><ssd:ParameterBinding>'
            f'<ssd:ParameterValues><ssv:ParameterSet version="1.0" name="p"><ssv:Parameters>{ps}'
            '<ssv:Parameter name="coupled"><ssv:Boolean value="true"/></ssv:Parameter></ssv:Parameters></ssv:ParameterSet>'
            "</ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings></ssd:Component>"
        )

    def conn(a, x, b, y):
        return f'<ssd:Connection startElement="{a}" startConnector="{x}" endElement="{b}" endConnector="{y}"/>'

    xml = (
        '<?xml version="1.0" encoding="UTF-8"?>'
        '<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
        'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
        'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="TwoMotors">'
        '<ssd:System name="TwoMotors"><ssd:Elements>'
        + motor("motor_a", a)
        + motor("motor_b", b)
        + '<ssd:Component name="load_a" source="resources/Feedthrough.fmu"/>'
        '<ssd:Component name="load_b" source="resources/Feedthrough.fmu"/>'
        "</ssd:Elements><ssd:Connections>"
        + conn("motor_a", "tau", "load_a", "Float64_continuous_input")
        + conn("load_a", "Float64_continuous_output", "motor_b", "omega")
        + conn("motor_b", "tau", "load_b", "Float64_continuous_input")
        + conn("load_b", "Float64_continuous_output", "motor_a", "omega")
        + "</ssd:Connections></ssd:System></ssd:SystemStructureDescription>"
    )
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("SystemStructure.ssd", xml)
        z.write(dcmotor, "resources/DCMotor.fmu")
        z.write(feedthrough, "resources/Feedthrough.fmu")
    return str(path)


def independent(stop, h, a=A, b=B):
    """Rows [i_a, i_b, tau_a, tau_b] at t = k h: the loop solved by numpy, the currents stepped exactly."""
    n = round(stop / h)
    i = np.array([a["i"], b["i"]])
    loop = np.array([[1.0, b["B"]], [a["B"], 1.0]])
    r, l, kb, u = (np.array([a[k], b[k]]) for k in ("R", "L", "kb", "U"))
    decay = np.exp(-r * h / l)
    rows = []
    for _ in range(n + 1):
        w_a, w_b = np.linalg.solve(loop, [b["km"] * i[1], a["km"] * i[0]])
        rows.append([i[0], i[1], w_b, w_a])  # tau_a drives load_a, the speed of motor_b
        i = i * decay + (u - kb * np.array([w_a, w_b])) * (1 - decay) / r
    return np.array(rows)


CASES = {
    "fmi2": (lambda: fmu("DCMotor"), lambda: fmu("Feedthrough"), True),
    "fmi3": (lambda: fmu3("DCMotor"), lambda: fmu3("Feedthrough"), True),
    "fmi3-reference-feedthrough": (lambda: fmu3("DCMotor"), lambda: theirs("Feedthrough"), False),
}


@pytest.mark.parametrize("case", CASES)
def test_the_loop_is_the_independent_solution_with_the_jacobian_the_components_allow(case, tmp_path):
    dcmotor, feedthrough, exact = CASES[case]
    s = rustfmu_runner.System(system(tmp_path / "loop.ssp", dcmotor(), feedthrough()))
    r = s.run(1.0, 1e-2, record=RECORD)
    got = np.column_stack([r[n] for n in RECORD])
    error = float(np.max(np.abs(got - independent(1.0, 1e-2))))
    (report,) = s.last_run["loops"]
    print(f"{case}: {report}; largest |runner - numpy| = {error:.3g}")
    assert error < 1e-12, f"{case}: the runner differs from the loop solved by numpy by {error}"
    assert report["exact_jacobian"] is exact, report
    assert report["components"] == ["motor_a", "motor_b", "load_a", "load_b"]
    assert report["most_iterations"] == 1 and report["solves"] == 105, report


def test_finite_differences_asked_for_give_the_same_numbers_and_options_are_checked(tmp_path):
    s = rustfmu_runner.System(system(tmp_path / "loop.ssp", fmu("DCMotor"), fmu("Feedthrough")))
    exact = s.run(1.0, 1e-2, record=RECORD)
    fd = s.run(1.0, 1e-2, record=RECORD, loops={"finite_differences": True, "rtol": 1e-12, "atol": 1e-12})
    assert s.last_run["loops"][0]["exact_jacobian"] is False
    worst = max(float(np.max(np.abs(exact[n] - fd[n]))) for n in RECORD)
    assert worst < 1e-12, worst
    with pytest.raises(rustfmu_runner.VariableError, match="no option 'tol'"):
        s.run(0.1, 1e-2, loops={"tol": 1e-6})


def test_a_singular_loop_raises_loop_error_with_component_time_and_residual(tmp_path):
    path = system(tmp_path / "singular.ssp", fmu("DCMotor"), fmu("Feedthrough"), {**A, "B": 1.0}, {**B, "B": 1.0})
    s = rustfmu_runner.System(path)
    with pytest.raises(rustfmu_runner.LoopError) as e:
        s.run(1.0, 1e-2, record=RECORD)
    err = e.value
    assert isinstance(err, rustfmu_runner.RunnerError)
    assert (err.component, err.time) == ("motor_a", 0.0), str(err)
    assert "singular" in str(err) and "unknowns motor_a.omega, motor_b.omega" in str(err) and "residual max" in str(err)
    assert len(err.partial["time"]) == 0


def test_the_command_line_lists_the_loop_and_says_what_it_took(tmp_path):
    if not CLI.exists():
        pytest.fail(f"{CLI} is missing: cargo build --release -p rustfmu-runner")
    path = system(tmp_path / "loop.ssp", fmu("DCMotor"), fmu("Feedthrough"))
    info = subprocess.run([str(CLI), "info", path], capture_output=True, text=True, check=True).stdout
    assert "algebraic loop among motor_a, motor_b, load_a, load_b (solved by Newton's method" in info, info
    run = [str(CLI), "run", path, "--stop-time", "1", "--step", "1e-2", "--no-progress", "-o", str(tmp_path / "o.csv")]
    out = subprocess.run([*run, "--loop-finite-differences"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "finite-difference Jacobian, 105 solves, 101 Newton iterations" in out.stderr, out.stderr
    out = subprocess.run([*run, "--loop-max-iterations", "0"], capture_output=True, text=True)
    assert out.returncode == 1 and "did not converge in 0 iterations" in out.stderr, out.stderr
