"""FMI 3.0 co-simulation FMUs in the native runner (issue 26): the SSP files of the FMI 3.0 FMUs
(target/fmu/fmi3/*.ssp, written by `cargo fmu build` next to today's), alone and mixed with FMI 2.0
components, against the runner on the FMI 2.0 files and against the project's fmpy master
(examples/cosim, FMU3Slave; fmpy's own simulate_ssp imports FMI 2.0 FMUs only)."""

import io
import zipfile

import numpy as np
import pytest
from conftest import FMU_DIR
from test_runner import cli, fmpy_reference, ssp

import rustfmu_runner

SYSTEMS = ["PendulumLQR", "PendulumMotors"]


def ssp3(name: str) -> str:
    path = FMU_DIR / "fmi3" / f"{name}.ssp"
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo fmu build --workspace` (it writes the SSP files)")
    return str(path)


@pytest.mark.parametrize("name", SYSTEMS)
def test_the_fmi3_ssp_file_runs_as_its_fmi2_twin(name):
    """The same models through FMI 3.0 (Float64, Int32, the Controller's mode as an Int64
    Enumeration, fmi3DoStep): every output equal to the FMI 2.0 file's, bit for bit."""
    a = rustfmu_runner.System(ssp(name))
    b = rustfmu_runner.System(ssp3(name))
    assert b.components == a.components and b.evaluation_order == a.evaluation_order
    ra, rb = a.run(2.0, 1e-3), b.run(2.0, 1e-3)
    assert set(ra) == set(rb)
    for k in ra:
        assert np.array_equal(ra[k], rb[k]), k
    assert rb["pendulum.alpha1"][0] == 0.1 and abs(rb["pendulum.alpha1"][-1]) < 0.05


@pytest.mark.parametrize("name", SYSTEMS)
def test_the_fmi3_ssp_file_in_the_runner_equals_the_fmpy_master(name, tmp_path):
    record = ["pendulum.alpha1", "pendulum.alpha2", "controller.M1", "controller.M2"]
    r = rustfmu_runner.System(ssp3(name)).run(1.0, 1e-3, record=record)
    ref = fmpy_reference(ssp3(name), tmp_path, 1.0, 1e-3, record)
    for x in record:
        assert np.max(np.abs(np.asarray(r[x]) - np.asarray(ref[x]))) == 0.0, x


def mixed(tmp_path) -> str:
    """PendulumLQR.ssp with the Pendulum of FMI 3.0 and the Controller of FMI 2.0."""
    out = tmp_path / "Mixed.ssp"
    with zipfile.ZipFile(ssp("PendulumLQR")) as src, zipfile.ZipFile(out, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "resources/Pendulum.fmu":
                data = (FMU_DIR / "fmi3" / "Pendulum.fmu").read_bytes()
            dst.writestr(item, data)
    return str(out)


def test_a_system_mixes_fmi2_and_fmi3_components(tmp_path):
    s = rustfmu_runner.System(mixed(tmp_path))
    versions = {}
    for c in ["pendulum", "controller"]:
        with zipfile.ZipFile(s.path) as z, zipfile.ZipFile(io.BytesIO(z.read(f"resources/{c.title()}.fmu"))) as f:
            versions[c] = b'fmiVersion="3.0"' in f.read("modelDescription.xml")
    assert versions == {"pendulum": True, "controller": False}
    a = rustfmu_runner.System(ssp("PendulumLQR")).run(2.0, 1e-3)
    b = s.run(2.0, 1e-3)
    for k in a:
        assert np.array_equal(a[k], b[k]), k


def test_error_controlled_steps_set_fmi3_states_back():
    """Rollback through fmi3GetFMUState / fmi3SetFMUState: the same steps and values as with the
    FMI 2.0 components."""
    rec = ["pendulum.alpha1", "motor1.tau"]
    a = rustfmu_runner.System(ssp("PendulumMotors"))
    b = rustfmu_runner.System(ssp3("PendulumMotors"))
    ra = a.run(0.5, 1e-3, record=rec, tolerance=1e-4)
    rb = b.run(0.5, 1e-3, record=rec, tolerance=1e-4)
    assert a.last_run == b.last_run and b.last_run["rejected"] >= 0
    for k in ra:
        assert np.array_equal(ra[k], rb[k]), k


def test_a_float32_parameter_is_set_and_failing_calls_have_their_fmi3_names(tmp_path):
    """Feedthrough (FMI 3.0) has Float32 variables: a parameter binding to one is set with
    fmi3SetFloat32 (every type: test_runner_fmi3_types.py); the FMI 3.0 component's failing calls
    are named with their FMI 3.0 names."""
    ssd = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="F">
  <ssd:System name="F">
    <ssd:Elements>
      <ssd:Component name="f" source="resources/Feedthrough.fmu" type="application/x-fmu-sharedlibrary">
        <ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="1.0" name="p"><ssv:Parameters>
          <ssv:Parameter name="PARAM"><ssv:Real value="VALUE"/></ssv:Parameter>
        </ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>
      </ssd:Component>
    </ssd:Elements>
  </ssd:System>
</ssd:SystemStructureDescription>"""

    def file(param, value):
        out = tmp_path / f"{param}.ssp"
        with zipfile.ZipFile(out, "w") as z:
            z.writestr("SystemStructure.ssd", ssd.replace("PARAM", param).replace("VALUE", value))
            z.writestr("resources/Feedthrough.fmu", (FMU_DIR / "fmi3" / "Feedthrough.fmu").read_bytes())
        return str(out)

    out = cli("run", file("Float32_continuous_input", "1.5"), "--stop-time", "0.01", "--step", "1e-3",
              "--record", "f.Float32_continuous_output", "--no-progress")
    assert out.returncode == 0 and [r.split(",")[1] for r in out.stdout.splitlines()[1:]] == ["1.5"] * 11, out
    # A Float64 parameter it reads; a value outside its range is the FMU's fmi3SetFloat64 error.
    s = rustfmu_runner.System(file("Float64_fixed_parameter", "2.5"))
    r = s.run(0.01, 1e-3, record=["f.Float64_continuous_output"])
    assert len(r["time"]) == 11
    out = cli("run", file("Float64_fixed_parameter", "nan"), "--stop-time", "0.01", "--step", "1e-3",
              "--record", "f.Float64_continuous_output", "--no-progress")
    assert out.returncode != 0 and "fmi3SetFloat64" in out.stderr, out.stderr


def test_a_connection_between_different_units_is_refused_across_versions(tmp_path):
    """The FMI 3.0 Pendulum's angular velocity (rad/s) into the FMI 2.0 Controller's angle input
    (rad): refused, naming both units (the runner converts none)."""
    import re

    path = mixed(tmp_path)
    out = tmp_path / "Units.ssp"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(out, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "SystemStructure.ssd":
                text, n = re.subn(
                    r'startElement="pendulum" startConnector="alpha1" endElement="controller" endConnector="alpha1"',
                    'startElement="pendulum" startConnector="omega1" endElement="controller" endConnector="alpha1"',
                    data.decode(),
                )
                assert n == 1
                data = text.encode()
            dst.writestr(item, data)
    with pytest.raises(rustfmu_runner.RunnerError, match=r"pendulum\.omega1 -> controller\.alpha1: from unit 'rad/s' to unit 'rad'"):
        rustfmu_runner.System(str(out))
