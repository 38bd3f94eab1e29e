"""A system of FMI 3.0 FMUs with arrays and Enumerations, written by `cargo fmu ssp` in SSP 2.0
(array connectors sized by structural parameters, array values as lists with their dimensions,
Enumeration connectors and an Enumeration value by its item's name): valid against the SSP 2.0
schemas, and run by the runner to the values fmpy gives for the same FMUs connected by hand.

The FMUs: two Reference StateSpace FMUs (arrays sized by structural parameters), s1.y into s2.u;
two Reference Feedthroughs, f1's Enumeration_output into f2's Enumeration_input; our Controller,
its Enumeration `mode` given by its item's name."""

import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave
from lxml import etree

from test_runner import cli
from test_runner_fmi3_types import REF, need, ours, read_csv
from test_ssp2 import CARGO_FMU, schema

A1 = [[-1.0, 0.0, 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, -3.0]]
X1 = [1.0, 0.5, -1.0]
A2 = [[-0.5, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.5]]
D2 = [[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.5]]
STOP, STEP = 1.0, 0.1

SYSTEMS = f"""[[system]]
name = "ArraysEnumerations"
fmi-version = "3.0"
connections = ["s1.y -> s2.u", "f1.Enumeration_output -> f2.Enumeration_input"]
[[system.component]]
name = "s1"
fmu = "StateSpace"
parameters = {{ A = {A1}, x0 = {X1} }}
[[system.component]]
name = "s2"
fmu = "StateSpace"
parameters = {{ A = {A2}, D = {D2} }}
[[system.component]]
name = "f1"
fmu = "Feedthrough"
[[system.component]]
name = "f2"
fmu = "Feedthrough"
[[system.component]]
name = "c"
fmu = "Controller"
parameters = {{ mode = "PID" }}
"""


def write(d, systems):
    """`cargo fmu ssp` on `systems` with the Reference FMUs and our Controller in `d`/fmi3."""
    (d / "fmi3").mkdir(exist_ok=True)
    for name in ["StateSpace", "Feedthrough"]:
        shutil.copy(need(REF / f"{name}.fmu"), d / "fmi3" / f"{name}.fmu")
    shutil.copy(ours("Controller"), d / "fmi3" / "Controller.fmu")
    (d / "systems.toml").write_text(systems)
    return subprocess.run([str(CARGO_FMU), "fmu", "ssp", "--systems", str(d / "systems.toml"), "--fmu-dir", str(d)],
                          capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    d = tmp_path_factory.mktemp("arrays")
    out = write(d, SYSTEMS)
    assert out.returncode == 0, out.stderr
    return d / "fmi3" / "ArraysEnumerations.ssp"


def test_the_written_ssd_is_valid_against_the_ssp2_schemas(written):
    with zipfile.ZipFile(written) as z:
        doc = etree.fromstring(z.read("SystemStructure.ssd"))
    s = schema("SystemStructureDescription.xsd")
    assert s.validate(doc), s.error_log
    ssv = schema("SystemStructureParameterValues.xsd")
    ns = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
          "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
          "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon"}
    sets = doc.findall(".//ssv:ParameterSet", ns)
    assert len(sets) == 3
    for p in sets:
        assert ssv.validate(etree.fromstring(etree.tostring(p))), ssv.error_log
    # An array connector sized by its structural parameter, itself a connector.
    y = doc.find(".//ssd:Component[@name='s1']/ssd:Connectors/ssd:Connector[@name='y']", ns)
    assert [d.get("sizeConnector") for d in y.findall("ssc:Dimension", ns)] == ["r"]
    assert doc.find(".//ssd:Component[@name='s1']/ssd:Connectors/ssd:Connector[@name='r']", ns).get("kind") == \
        "structuralParameter"
    a = doc.find(".//ssd:Component[@name='s1']//ssv:Parameter[@name='A']", ns)
    assert [float(x) for x in a.find("ssv:Float64", ns).get("value").split()] == sum(A1, [])
    assert [d.get("size") for d in a.findall("ssc:Dimension", ns)] == ["3", "3"]
    mode = doc.find(".//ssv:Parameter[@name='mode']/ssv:Enumeration", ns)
    assert (mode.get("value"), mode.get("name")) == ("PID", "ControlMode")
    items = doc.findall(".//ssd:Enumerations/ssc:Enumeration[@name='Option']/ssc:Item", ns)
    assert [(i.get("name"), i.get("value")) for i in items] == [("Option 1", "1"), ("Option 2", "2")]


def by_hand(tmp_path):
    """fmpy on the two StateSpace FMUs, s1.y into s2.u at each communication point (s1 first,
    as the runner's Gauss-Seidel order), with the system's parameter values: s2.y per row."""
    path = need(REF / "StateSpace.fmu")
    md = read_model_description(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extract(path, str(tmp_path / "by_hand"))
    s1, s2 = (FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName=n) for n in ("s1", "s2"))
    for s, values in [(s1, {"A": A1, "x0": X1}), (s2, {"A": A2, "D": D2})]:
        s.instantiate()
        for name, x in values.items():
            s.setFloat64([vr[name]], list(np.ravel(x)))
        s.enterInitializationMode(startTime=0.0)
        s.exitInitializationMode()
    rows, t = [], 0.0
    n = round(STOP / STEP)
    for k in range(n + 1):
        s2.setFloat64([vr["u"]], s1.getFloat64([vr["y"]], nValues=3))
        rows.append(s2.getFloat64([vr["y"]], nValues=3))
        if k < n:
            for s in (s1, s2):
                s.doStep(currentCommunicationPoint=t, communicationStepSize=STEP)
            t = (k + 1) * STEP
    for s in (s1, s2):
        s.terminate()
        s.freeInstance()
    return np.array(rows)


def test_the_runner_gives_the_arrays_and_enumerations_fmpy_gives(written, tmp_path):
    out = tmp_path / "run.csv"
    r = cli("run", written, "--stop-time", STOP, "--step", STEP, "--no-progress", "--output", out,
            "--set", "f1.Enumeration_input=2", "--record", "s1.y", "--record", "s2.y",
            "--record", "f2.Enumeration_output", "--record", "c.mode")
    assert r.returncode == 0, r.stderr
    got = read_csv(out)
    y2 = np.column_stack([got[f"s2.y[{i}]"] for i in (1, 2, 3)])
    ref = by_hand(tmp_path)
    assert y2.shape == ref.shape and np.max(np.abs(y2 - ref)) <= 1e-12, (y2, ref)
    # s1's outputs reached s2 through the array connection: at t = 0, x2 = 0 and y2 = D2 y1, y1
    # s1's u (start 1 2 3) through its D = I.
    y1 = np.column_stack([got[f"s1.y[{i}]"] for i in (1, 2, 3)])
    assert np.array_equal(y1[0], [1.0, 2.0, 3.0]) and np.array_equal(y2[0], 0.5 * y1[0]), (y1[0], y2[0])
    # The Enumeration: f1's item 2 through the connection; mode "PID" set as its value 2.
    assert np.all(got["f2.Enumeration_output"] == 2), got["f2.Enumeration_output"]
    assert np.all(got["c.mode"] == 2), got["c.mode"]


def test_arrays_of_other_dimensions_are_refused_naming_both_ends(tmp_path):
    out = write(tmp_path, SYSTEMS.replace("parameters = { A = [[-0.5", "parameters = { m = 2, A = [[-0.5"))
    assert out.returncode != 0
    assert "connection s1.y -> s2.u" in out.stderr and "s1.y is [r = 3], s2.u is [m = 2]" in out.stderr, out.stderr
