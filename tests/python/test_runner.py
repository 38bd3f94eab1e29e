"""The native SSP runner (runner/, the rustfmu_runner module and the rustfmu-runner command line)
against the project's fmpy master (examples/cosim/master.py), the reference: the same numbers on
every SSP file the project writes and on an SSD of FMUs made with `cargo fmu new`; numpy arrays
back; errors that name component and variable; a failed run recorded while the study goes on."""

import os
import pathlib
import re
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from conftest import FMU_DIR, ROOT, USER_TARGET, fmu, outside_crate

sys.path.insert(0, str(ROOT / "examples"))
import rustfmu_runner  # noqa: E402
from cosim.master import Component, Connection, System, simulate  # noqa: E402
from cosim.systems import read_ssp  # noqa: E402

TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
CLI = TARGET / "release" / "rustfmu-runner"
SSP_FILES = sorted(FMU_DIR.glob("*.ssp"))


def ssp(name: str) -> str:
    path = FMU_DIR / f"{name}.ssp"
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo run --release -p fmu-build` first")
    return str(path)


def fmpy_reference(ssp_path, tmp_path, stop, step, record, start=None):
    """The fmpy master on the system of `ssp_path`, with the FMUs inside the archive."""
    system = read_ssp(ssp_path)
    with zipfile.ZipFile(ssp_path) as z:
        z.extractall(tmp_path / "ssp")
    components = []
    for c in system.components:
        values = dict(c.start)
        for k, v in (start or {}).items():
            if k.partition(".")[0] == c.name:
                values[k.partition(".")[2]] = v
        components.append(Component(c.name, str(tmp_path / "ssp" / "resources" / f"{c.fmu}.fmu"), values))
    system = System(system.name, tuple(components), system.connections)
    by_component = {}
    for name in record:
        c, _, v = name.partition(".")
        by_component.setdefault(c, []).append(v)
    return simulate(system, stop, step, by_component)


def largest_difference(native: dict, reference: dict, names) -> float:
    worst = 0.0
    for n in names:
        a, b = np.asarray(native[n]), np.asarray(reference[n])
        assert a.shape == b.shape, f"{n}: {a.shape} vs {b.shape}"
        worst = max(worst, float(np.max(np.abs(a - b))) if a.size else 0.0)
    return worst


def test_the_module_returns_numpy_arrays_per_communication_point():
    s = rustfmu_runner.System(ssp("PendulumMotors"))
    assert s.evaluation_order == ["pendulum", "controller", "motor1", "motor2"]
    assert ("motor1", "DCMotor") in s.components and "pendulum.alpha1_0" in s.parameters
    r = s.run(1.0, 1e-3, start={"pendulum.alpha1_0": 0.2, "controller.mode": 3}, record=["pendulum.alpha1", "controller.U1"])
    assert set(r) == {"time", "pendulum.alpha1", "controller.U1"}
    for v in r.values():
        assert isinstance(v, np.ndarray) and v.dtype == np.float64 and v.shape == (1001,)
    assert np.array_equal(r["time"], np.arange(1001) * 1e-3)
    assert r["pendulum.alpha1"][0] == 0.2
    # Default record: every output.
    full = s.run(0.01, 1e-3)
    assert set(full) == {"time", *s.outputs} and "motor2.tau" in full


@pytest.mark.parametrize("path", SSP_FILES, ids=[p.stem for p in SSP_FILES])
def test_the_runner_computes_what_the_fmpy_master_computes_on_every_ssp_file(path, tmp_path):
    assert SSP_FILES, f"no SSP files in {FMU_DIR}: run `cargo run --release -p fmu-build` first"
    s = rustfmu_runner.System(str(path))
    stop, step = 2.0, 1e-3
    start = {"pendulum.alpha1_0": 0.15} if any(c == "pendulum" for c, _ in s.components) else {}
    native = s.run(stop, step, start=start)
    reference = fmpy_reference(path, tmp_path, stop, step, s.outputs, start)
    worst = largest_difference(native, reference, ["time", *s.outputs])
    print(f"{path.name}: largest |native - fmpy| over {len(s.outputs)} outputs x {len(native['time'])} points = {worst:.3g}")
    assert worst == 0.0, f"{path.name}: the runner differs from the fmpy master by up to {worst}"


def test_an_unknown_variable_names_component_variable_and_what_exists():
    s = rustfmu_runner.System(ssp("PendulumLQR"))
    with pytest.raises(rustfmu_runner.VariableError, match=r"component 'pendulum' \(Pendulum\): no variable 'alpha9_0'") as e:
        s.run(0.1, 1e-3, start={"pendulum.alpha9_0": 0.2})
    assert "alpha1_0" in str(e.value) and e.value.component == "pendulum" and e.value.variable == "alpha9_0"
    with pytest.raises(rustfmu_runner.VariableError, match="no component 'plant'"):
        s.run(0.1, 1e-3, record=["plant.alpha1"])


def test_an_fmu_error_names_component_variable_function_and_keeps_what_was_recorded():
    s = rustfmu_runner.System(ssp("PendulumLQR"))
    with pytest.raises(rustfmu_runner.FmuError) as e:
        s.run(0.1, 1e-3, start={"pendulum.m1": -0.5}, record=["pendulum.alpha1"])
    err = e.value
    assert (err.component, err.variable, err.function, err.status) == ("pendulum", "m1", "fmi2SetReal", "Error"), str(err)
    assert "outside (0, inf)" in str(err) and "[pendulum: Error]" in str(err), str(err)
    assert len(err.partial["time"]) == 0
    # The same System runs again.
    assert len(s.run(0.1, 1e-3, record=["pendulum.alpha1"])["time"]) == 101


def rewritten_zip(source, out, edit) -> str:
    """A copy of the archive `source` (an SSP file, an FMU) at `out`, each member's bytes passed
    through `edit(name, data)`."""
    with zipfile.ZipFile(source) as src, zipfile.ZipFile(out, "w") as dst:
        for item in src.infolist():
            dst.writestr(item, edit(item.filename, src.read(item.filename)))
    return str(out)


def rewritten_ssp(tmp_path, name, edit, out_name=None) -> str:
    """A copy of target/fmu/<name>.ssp (as tmp_path/`out_name`, by default <name>-edited.ssp)
    with its SystemStructure.ssd passed through `edit`."""

    def ssd(member, data):
        return edit(data.decode()).encode() if member == "SystemStructure.ssd" else data

    return rewritten_zip(ssp(name), tmp_path / (out_name or f"{name}-edited.ssp"), ssd)


def test_an_ssp_it_cannot_run_is_refused_naming_component_and_connector(tmp_path):
    def to_system_connector(ssd):
        new, n = re.subn(r'startElement="controller" startConnector="M1"', 'startConnector="M1"', ssd, count=1)
        assert n == 1, ssd
        return new

    with pytest.raises(rustfmu_runner.SspError, match=r"connection <system>\.M1 -> pendulum\.M1: the system 'PendulumLQR' has no connector 'M1'"):
        rustfmu_runner.System(rewritten_ssp(tmp_path, "PendulumLQR", to_system_connector))

    def to_system_output(ssd):
        # A system connector of kind output that feeds a component: refused with its kind.
        new = to_system_connector(ssd)
        return new.replace("<ssd:Elements>", '<ssd:Connectors><ssd:Connector name="M1" kind="output"><ssc:Real/></ssd:Connector></ssd:Connectors><ssd:Elements>', 1)

    with pytest.raises(rustfmu_runner.SspError, match=r"the system's connector 'M1' is of kind 'output'"):
        rustfmu_runner.System(rewritten_ssp(tmp_path, "PendulumLQR", to_system_output))

    def scaled(ssd):
        return re.sub(r'(startElement="controller" startConnector="M1"[^>]*)/>', r'\1><ssc:LinearTransformation factor="2"/></ssd:Connection>', ssd, count=1)

    with pytest.raises(rustfmu_runner.SspError, match="controller.M1 -> pendulum.M1: ssc:LinearTransformation is not supported") as e:
        rustfmu_runner.System(rewritten_ssp(tmp_path, "PendulumLQR", scaled))
    assert (e.value.component, e.value.variable) == ("pendulum", "M1")


def cli(*args):
    if not CLI.exists():
        subprocess.run(["cargo", "build", "--release", "-q", "-p", "rustfmu-runner", "--bin", "rustfmu-runner"], cwd=ROOT, check=True)
    return subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True, timeout=300)


def test_the_command_line_names_an_unknown_variable_in_set():
    out = cli("run", ssp("PendulumMotors"), "--stop-time", "0.01", "--step", "1e-3", "--set", "pendulum.alpha9_0=0.2", "--no-progress")
    assert out.returncode == 1, out
    assert "rustfmu-runner: error: component 'pendulum' (Pendulum): no variable 'alpha9_0'" in out.stderr, out.stderr
    out = cli("run", ssp("PendulumMotors"), "--step", "1e-3", "--set", "pendulum.alpha1_0", "--no-progress")
    assert out.returncode == 1 and "expected COMPONENT.VARIABLE=VALUE" in out.stderr, out.stderr


def test_the_command_line_writes_the_modules_numbers(tmp_path):
    csv = tmp_path / "out.csv"
    out = cli(
        "run", ssp("PendulumMotors"), "--stop-time", "0.5", "--step", "1e-3", "--set", "pendulum.alpha1_0=0.2",
        "--set", "controller.mode=1", "--record", "pendulum.alpha1", "--record", "motor1.tau", "--output", csv,
    )
    assert out.returncode == 0, out.stderr
    data = np.genfromtxt(csv, delimiter=",", names=True)
    assert data.dtype.names == ("time", "pendulumalpha1", "motor1tau")
    r = rustfmu_runner.System(ssp("PendulumMotors")).run(0.5, 1e-3, start={"pendulum.alpha1_0": 0.2, "controller.mode": 1}, record=["pendulum.alpha1", "motor1.tau"])
    assert np.array_equal(data["pendulumalpha1"], r["pendulum.alpha1"]) and np.array_equal(data["motor1tau"], r["motor1.tau"])


# -- An SSD of FMUs made with `cargo fmu new` (a first-order lag), ring of three ------------

LAG_SSD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="Lags">
  <ssd:System name="LagRing">
    <ssd:Elements>
      <ssd:Component name="lag1" source="resources/MyLag.fmu" type="application/x-fmu-sharedlibrary">
        <ssd:Connectors><ssd:Connector name="u" kind="input"><ssc:Real/></ssd:Connector><ssd:Connector name="y" kind="output"><ssc:Real/></ssd:Connector></ssd:Connectors>
        <ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="1.0" name="p"><ssv:Parameters>
          <ssv:Parameter name="T"><ssv:Real value="0.2"/></ssv:Parameter>
          <ssv:Parameter name="y"><ssv:Real value="1.0"/></ssv:Parameter>
        </ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>
      </ssd:Component>
      <ssd:Component name="lag2" source="resources/MyLag.fmu">
        <ssd:ParameterBindings><ssd:ParameterBinding source="resources/lag2.ssv"/></ssd:ParameterBindings>
      </ssd:Component>
      <ssd:Component name="lag3" source="resources/MyLag.fmu"/>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="lag1" startConnector="y" endElement="lag2" endConnector="u"/>
      <ssd:Connection startElement="lag2" startConnector="y" endElement="lag3" endConnector="u"/>
      <ssd:Connection startElement="lag3" startConnector="y" endElement="lag1" endConnector="u"/>
    </ssd:Connections>
  </ssd:System>
</ssd:SystemStructureDescription>
"""

LAG2_SSV = """<?xml version="1.0" encoding="UTF-8"?>
<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="lag2">
  <ssv:Parameters><ssv:Parameter name="T"><ssv:Real value="0.05"/></ssv:Parameter></ssv:Parameters>
</ssv:ParameterSet>
"""


@pytest.fixture(scope="module")
def my_lag_fmu():
    """MyLag.fmu of a crate made by `cargo fmu new my-lag` (unchanged), outside this workspace,
    built into the tests' shared target folder of such crates (kept, so that a second test run
    builds nothing)."""
    crate, env = outside_crate("my-lag")
    out = subprocess.run(["nice", "-n", "10", "cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=1800)
    assert out.returncode == 0, out.stderr
    path = USER_TARGET / "fmu" / "MyLag.fmu"
    assert path.exists(), out.stderr
    return path


def test_an_ssd_of_cargo_fmu_new_fmus_runs_as_in_the_fmpy_master(my_lag_fmu, tmp_path):
    ssp_path = tmp_path / "LagRing.ssp"
    with zipfile.ZipFile(ssp_path, "w") as z:
        z.writestr("SystemStructure.ssd", LAG_SSD)
        z.writestr("resources/lag2.ssv", LAG2_SSV)
        z.write(my_lag_fmu, "resources/MyLag.fmu")
    s = rustfmu_runner.System(str(ssp_path))
    assert s.parameters == ["lag1.T", "lag1.y", "lag2.T"]
    names = ["lag1.y", "lag2.y", "lag3.y"]
    native = s.run(3.0, 1e-2, start={"lag3.T": 0.5}, record=names)
    lag = str(my_lag_fmu)
    system = System(
        "LagRing",
        (Component("lag1", lag, {"T": 0.2, "y": 1.0}), Component("lag2", lag, {"T": 0.05}), Component("lag3", lag, {"T": 0.5})),
        (Connection("lag1", "y", "lag2", "u"), Connection("lag2", "y", "lag3", "u"), Connection("lag3", "y", "lag1", "u")),
    )
    reference = simulate(system, 3.0, 1e-2, {"lag1": ["y"], "lag2": ["y"], "lag3": ["y"]})
    worst = largest_difference(native, reference, ["time", *names])
    print(f"LagRing (cargo fmu new): largest |native - fmpy| = {worst:.3g}")
    assert worst == 0.0
    assert native["lag1.y"][0] == 1.0 and 0.1 < native["lag3.y"][-1] < 1.0, native["lag3.y"][-1]


# -- The parameter study on both masters ----------------------------------------------------


def test_the_study_gives_the_same_rows_on_both_masters_and_a_failed_run_is_recorded():
    from pendulum_study import runner, studies

    paths = {name: fmu(name) for name in ("Pendulum", "Controller", "DCMotor")}
    specs = studies.region_of_attraction(modes=(1, 2), n=2, amax=0.3, stop_time=2.0, step=1e-2)
    specs += [runner.make_spec("torque", {"controller.mode": 1, "pendulum.m1": -0.5}, 2.0, 1e-2)]
    specs += [runner.make_spec("torque", {"controller.mode": 1, "pendulum.alpha1_0": 1.4, "pendulum.alpha2_0": 1.4}, 2.0, 1e-2)]
    specs += studies.robustness(paths, 2, 0.2, 1, (1, 3), "motors", stop_time=1.0, step=1e-3)
    native = runner.run_sequential(specs, paths, master="native")
    fmpy = runner.run_sequential(specs, paths, master="fmpy")
    compared = [c for c in runner.RESULT_COLUMNS if c not in runner.BOOKKEEPING_COLUMNS and c != "error"]
    worst = 0.0
    for a, b in zip(native, fmpy):
        assert a["run_id"] == b["run_id"]
        for c in compared:
            x, y = a[c], b[c]
            if isinstance(x, float) and isinstance(y, float):
                assert x == y or (np.isnan(x) and np.isnan(y)), f"run {a['run_id']} {c}: native {x!r}, fmpy {y!r}"
                if not np.isnan(x):
                    worst = max(worst, abs(x - y))
            else:
                assert x == y, f"run {a['run_id']} {c}: native {x!r}, fmpy {y!r}"
    print(f"largest native - fmpy difference over {len(specs)} rows: {worst}")
    statuses = [r["status"] for r in native]
    assert statuses.count("failed") == 1 and statuses[-1] == "ok", statuses
    bad = native[statuses.index("failed")]
    assert (bad["fmi_status"], bad["fmi_function"]) == ("Error", "fmi2SetReal"), bad
    assert "component 'pendulum'" in bad["error"] and "'m1'" in bad["error"], bad["error"]
    assert "fell" in [r["outcome"] for r in native]
    assert {r["master"] for r in native} == {"native"} and {r["master"] for r in fmpy} == {"fmpy"}
