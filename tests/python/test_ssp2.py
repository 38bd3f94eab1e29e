"""SSP 2.0: `cargo fmu build` writes the FMI 3.0 archive of a system in SSP 2.0 when its systems
file asks (`ssp-version = "2.0"`), valid against the SSP 2.0 schemas (lxml, the standard's own
XSD files); the runner reads it and gives the rows of the same system in SSP 1.0 and of the fmpy
master; a schema-invalid SSP 2.0 file is refused with its element and line."""

import io
import pathlib
import re
import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from lxml import etree

from conftest import FMU_DIR, ROOT
from test_runner import cli, fmpy_reference

SCHEMA = ROOT.parent / "shared" / "independent" / "ssp-standard-2.0" / "schema"
CARGO_FMU = FMU_DIR.parent / "release" / "cargo-fmu"
SYSTEMS = ["PendulumLQR", "PendulumMotors"]
RECORD = ["pendulum.alpha1", "pendulum.alpha2", "controller.M1", "controller.M2"]


def schema(name):
    return etree.XMLSchema(etree.parse(str(SCHEMA / name)))


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """The project's systems with `ssp-version = "2.0"`, written by cargo fmu from copies of
    the packaged FMUs: {system: path of its SSP 2.0 archive}."""
    d = tmp_path_factory.mktemp("ssp2")
    (d / "fmi3").mkdir()
    for f in FMU_DIR.glob("*.fmu"):
        shutil.copy(f, d / f.name)
    for f in (FMU_DIR / "fmi3").glob("*.fmu"):
        shutil.copy(f, d / "fmi3" / f.name)
    text = (ROOT / "holonomic" / "systems.toml").read_text()
    (d / "systems.toml").write_text(text.replace("[[system]]\n", '[[system]]\nssp-version = "2.0"\n'))
    out = subprocess.run([str(CARGO_FMU), "fmu", "ssp", "--systems", str(d / "systems.toml"), "--fmu-dir", str(d)],
                         capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert out.returncode == 0, out.stderr
    return {s: d / "fmi3" / f"{s}.ssp" for s in SYSTEMS}


def ssd_of(path):
    with zipfile.ZipFile(path) as z:
        return z.read("SystemStructure.ssd")


@pytest.mark.parametrize("name", SYSTEMS)
def test_the_written_ssp2_is_valid_against_the_ssp2_schema(written, name):
    xml = ssd_of(written[name])
    doc = etree.fromstring(xml)
    assert doc.get("version") == "2.0"
    s = schema("SystemStructureDescription.xsd")
    assert s.validate(doc), s.error_log
    # Its inline parameter sets against the SSV 2.0 schema, and its FMI 3.0 types.
    ssv = schema("SystemStructureParameterValues.xsd")
    ns = {"ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
          "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon"}
    sets = doc.findall(".//ssv:ParameterSet", ns)
    assert sets and all(p.get("version") == "2.0" for p in sets)
    for p in sets:
        assert ssv.validate(etree.fromstring(etree.tostring(p))), ssv.error_log
    assert doc.findall(".//ssc:Float64", ns) and not doc.findall(".//ssc:Real", ns)
    assert doc.findall(".//ssv:Float64", ns) and not doc.findall(".//ssv:Real", ns)
    # The FMI 2.0 archive stays SSP 1.0.
    assert etree.fromstring(ssd_of(written[name].parent.parent / f"{name}.ssp")).get("version") == "1.0"


def run_csv(path, tmp_path, tag):
    csv = tmp_path / f"{tag}.csv"
    args = ["run", path, "--stop-time", "1.0", "--step", "1e-3", "--no-progress", "--output", csv]
    for r in RECORD:
        args += ["--record", r]
    out = cli(*args)
    assert out.returncode == 0, out.stderr
    return np.genfromtxt(csv, delimiter=",", names=True)


@pytest.mark.parametrize("name", SYSTEMS)
def test_the_ssp2_system_runs_as_its_ssp1_twin_and_the_fmpy_master(written, name, tmp_path):
    ssp1 = FMU_DIR / "fmi3" / f"{name}.ssp"
    a = run_csv(ssp1, tmp_path, "v1")
    b = run_csv(written[name], tmp_path, "v2")
    assert a.dtype.names == b.dtype.names and len(a) == 1001
    for k in a.dtype.names:
        assert np.array_equal(a[k], b[k]), k
    # fmpy reads SSP 1.0 only: its master runs the SSP 1.0 file of the same FMUs and values.
    ref = fmpy_reference(str(ssp1), tmp_path, 1.0, 1e-3, RECORD)
    for x in RECORD:
        assert np.max(np.abs(b[x.replace(".", "")] - np.asarray(ref[x]))) == 0.0, x


def with_ssd(src, tmp_path, edit, name="Bad.ssp"):
    """A copy of the archive `src` with its SSD edited by `edit(text) -> text`."""
    out = tmp_path / name
    with zipfile.ZipFile(src) as z, zipfile.ZipFile(out, "w") as w:
        for i in z.infolist():
            data = z.read(i)
            if i.filename == "SystemStructure.ssd":
                data = edit(data.decode()).encode()
            w.writestr(i, data)
    return out


def refused(path):
    out = cli("run", path, "--stop-time", "0.01", "--step", "1e-3", "--no-progress")
    assert out.returncode == 1, out
    return out.stderr


def line_of(text, needle):
    return text[: text.index(needle)].count("\n") + 1


BAD = {
    # a Connection before the Elements: out of the schema's sequence
    "order": (lambda t: t.replace("<ssd:Elements>", "<ssd:Connections><ssd:Connection startConnector=\"a\" endConnector=\"b\"/></ssd:Connections>\n    <ssd:Elements>", 1),
              "<ssd:Elements>", "ssd:Elements stands after ssd:Connections"),
    # a connector without its kind
    "required": (lambda t: re.sub(r'(<ssd:Connector name="[^"]+") kind="[^"]+"', r"\1", t, count=1),
                 "<ssd:Connector name", "ssd:Connector lacks the attribute kind"),
    # a kind the schema does not list
    "kind": (lambda t: t.replace('kind="output"', 'kind="out"', 1), 'kind="out"', 'kind="out" is not one of input'),
    # an element of SSP 1.0's Real type with a value that is no xs:double
    "value": (lambda t: re.sub(r'(<ssv:Float64 value=")[^"]+"', r'\1zero"', t, count=1), 'value="zero"', 'ssv:Float64 value="zero" is not a list of an xs:double'),
    # an unknown element
    "unknown": (lambda t: t.replace("<ssd:Elements>", "<ssd:Elements>\n      <ssd:Part name=\"x\"/>", 1), "<ssd:Part", "ssd:Part may not stand in ssd:Elements"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_schema_invalid_ssp2_is_refused_with_element_and_line(written, case, tmp_path):
    edit, needle, message = BAD[case]
    text = edit(ssd_of(written["PendulumLQR"]).decode())
    # lxml and the standard's schemas agree that it is invalid: the SSD's, or the SSV's for an
    # inline parameter set (SystemStructureDescription.xsd leaves ssd:ParameterValues open).
    doc = etree.fromstring(text.encode())
    ssv = schema("SystemStructureParameterValues.xsd")
    sets = doc.iter("{http://ssp-standard.org/SSP1/SystemStructureParameterValues}ParameterSet")
    assert not schema("SystemStructureDescription.xsd").validate(doc) or not all(
        ssv.validate(etree.fromstring(etree.tostring(p))) for p in sets)
    err = refused(with_ssd(written["PendulumLQR"], tmp_path, edit))
    assert f"SystemStructure.ssd:{line_of(text, needle)}: " in err and message in err, err


def test_malformed_xml_and_a_clock_connector_are_refused(written, tmp_path):
    err = refused(with_ssd(written["PendulumLQR"], tmp_path, lambda t: t.replace("</ssd:Elements>", "</ssd:Element>", 1)))
    assert "SystemStructure.ssd:" in err and "XML error" in err, err
    clock = with_ssd(written["PendulumLQR"], tmp_path,
                     lambda t: t.replace('kind="output"><ssc:Float64/>', 'kind="output"><ssc:Clock/>', 1), "Clock.ssp")
    err = refused(clock)
    assert "is no Clock connector: a Clock (ssc:Clock) connects to a Clock only" in err, err
    indices = with_ssd(written["PendulumLQR"], tmp_path,
                       lambda t: t.replace("<ssd:Connection ", '<ssd:Connection startIndices="1" ', 1), "Indices.ssp")
    assert "startIndices=\"1\"" in refused(indices)


from test_runner_fmi3_types import NUMERIC, REF, VALUES, fmusim, need, ours, runner, same  # noqa: E402

NS = ('xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
      'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
      'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"')
# The SSV 2.0 element of each Feedthrough input (the Enumeration's value as an Int64, its FMI 3.0
# representation; SSP's ssv:Enumeration takes an item name).
SSV2 = {"Float32_continuous": "Float32", "Float64_continuous": "Float64", "Int8": "Int8", "UInt8": "UInt8",
        "Int16": "Int16", "UInt16": "UInt16", "Int32": "Int32", "UInt32": "UInt32", "Int64": "Int64", "UInt64": "UInt64",
        "Boolean": "Boolean", "Enumeration": "Int64"}
# The SSD 2.0 connector type of each Feedthrough variable.
CONNECTOR = dict(SSV2, Enumeration="Enumeration")


def write_ssp2(out, components, connectors, connections, parameters):
    """An SSP 2.0 file: `components` [(name, fmu)], `connectors` {name: [(variable, kind, type,
    dims)]}, `connections` [(a, out, b, in)], `parameters` {name: [(variable, ssv type, value,
    dims)]}; returns (path, SSD text)."""
    elements = []
    for name, path in components:
        cs = "".join(f'<ssd:Connector name="{v}" kind="{k}">'
                     + (f'<ssc:Enumeration name="E"/>' if t == "Enumeration" else f"<ssc:{t}/>")
                     + "".join(f'<ssc:Dimension size="{d}"/>' for d in dims) + "</ssd:Connector>"
                     for v, k, t, dims in connectors.get(name, []))
        ps = "".join(f'<ssv:Parameter name="{v}"><ssv:{t} value="{x}"/>'
                     + "".join(f'<ssc:Dimension size="{d}"/>' for d in dims) + "</ssv:Parameter>"
                     for v, t, x, dims in parameters.get(name, []))
        binding = (f'<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="2.0" '
                   f'name="p"><ssv:Parameters>{ps}</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues>'
                   f'</ssd:ParameterBinding></ssd:ParameterBindings>') if ps else ""
        elements.append(f'<ssd:Component name="{name}" source="resources/{name}.fmu">'
                        + (f"<ssd:Connectors>{cs}</ssd:Connectors>" if cs else "") + f"{binding}</ssd:Component>")
    links = "".join(f'<ssd:Connection startElement="{a}" startConnector="{b}" endElement="{c}" endConnector="{d}"/>'
                    for a, b, c, d in connections)
    ssd = (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssd:SystemStructureDescription {NS} version="2.0" name="S">\n'
           f'<ssd:System name="S">\n<ssd:Elements>{"".join(elements)}</ssd:Elements>\n'
           + (f"<ssd:Connections>{links}</ssd:Connections>\n" if links else "") + "</ssd:System>\n"
           '<ssd:Enumerations><ssc:Enumeration name="E"><ssc:Item name="one" value="1"/><ssc:Item name="two" value="2"/>'
           "</ssc:Enumeration></ssd:Enumerations>\n</ssd:SystemStructureDescription>\n")
    with zipfile.ZipFile(out, "w") as z:
        z.writestr("SystemStructure.ssd", ssd)
        for name, path in components:
            z.write(path, f"resources/{name}.fmu")
    return str(out), ssd


def valid(ssd):
    doc = etree.fromstring(ssd.encode())
    s = schema("SystemStructureDescription.xsd")
    assert s.validate(doc), s.error_log
    ssv = schema("SystemStructureParameterValues.xsd")
    for p in doc.iter("{http://ssp-standard.org/SSP1/SystemStructureParameterValues}ParameterSet"):
        assert ssv.validate(etree.fromstring(etree.tostring(p))), ssv.error_log


def test_ssp2_typed_connectors_and_values_drive_feedthroughs_as_fmusim(tmp_path):
    """The Reference Feedthrough (C) into ours (Rust) through SSD 2.0 connectors of every FMI 3.0
    number type, its inputs set by SSV 2.0 values of those types (at the edges of their ranges),
    a Binary as hexadecimal digits: ours passes on what fmusim computes for the Reference one."""
    ref_fmu = need(REF / "Feedthrough.fmu")
    connectors = {
        "ref": [(f"{t}_output", "output", CONNECTOR[t], ()) for t in NUMERIC] + [("Binary_output", "output", "Binary", ())],
        "ours": [(f"{t}_input", "input", CONNECTOR[t], ()) for t in NUMERIC] + [("Binary_input", "input", "Binary", ())],
    }
    parameters = {"ref": [(f"{t}_input", SSV2[t], VALUES[t], ()) for t in NUMERIC] + [("Binary_input", "Binary", "00ff", ())]}
    links = [("ref", f"{t}_output", "ours", f"{t}_input") for t in NUMERIC + ["Binary"]]
    path, ssd = write_ssp2(tmp_path / "FF.ssp", [("ref", ref_fmu), ("ours", ours("Feedthrough"))], connectors, links,
                           parameters)
    valid(ssd)
    got = runner(tmp_path, path, 0.3, 0.1, *[a for t in NUMERIC for a in ("--record", f"ours.{t}_output")])
    ref = fmusim(tmp_path, ref_fmu, 0.3, 0.1, *[a for t in NUMERIC for a in ("--start-value", f"{t}_input", VALUES[t])])
    for t in NUMERIC:
        assert same(t, got[f"ours.{t}_output"], ref[f"{t}_output"]), t


def test_ssp2_array_connectors_and_array_values_equal_fmusim(tmp_path):
    """StateSpace's arrays in SSP 2.0: A and u given as SSV 2.0 Float64 lists with their
    ssc:Dimension (row-major), y an array connector of 3; against fmusim with the same starts."""
    fmu = need(REF / "StateSpace.fmu")
    u, a = "0.5 -1 2", "-1 0 0 0 -2 0 0 0 -3"
    path, ssd = write_ssp2(tmp_path / "S.ssp", [("s", fmu)], {"s": [("y", "output", "Float64", (3,))]}, [],
                           {"s": [("u", "Float64", u, (3,)), ("A", "Float64", a, (3, 3))]})
    valid(ssd)
    got = runner(tmp_path, path, 1.0, 0.25)
    ref = fmusim(tmp_path, fmu, 1.0, 0.25, "--start-value", "u", u, "--start-value", "A", a)
    y = np.column_stack([got[f"s.y[{i}]"] for i in (1, 2, 3)])
    assert np.max(np.abs(y - ref["y"])) <= 1e-15, (y, ref["y"])
    assert np.array_equal(y[0], [0.5, -1.0, 2.0])
    # A list of the wrong count, and of another type, refused naming the variable.
    path, _ = write_ssp2(tmp_path / "B.ssp", [("s", fmu)], {}, [], {"s": [("u", "Float64", "1 2", (2,))]})
    r = cli("run", path, "--stop-time", "0.1", "--step", "0.1", "--no-progress")
    assert r.returncode == 1 and "u (Float64[3])" in r.stderr and "2 value(s) given, the variable has 3" in r.stderr, r.stderr
    path, _ = write_ssp2(tmp_path / "C.ssp", [("s", fmu)], {}, [], {"s": [("u", "Int32", "1 2 3", (3,))]})
    r = cli("run", path, "--stop-time", "0.1", "--step", "0.1", "--no-progress")
    assert r.returncode == 1 and "an ssv:Int32 value for a Float64 variable" in r.stderr, r.stderr


def test_a_connector_type_or_size_other_than_its_variables_is_refused(tmp_path):
    """SSP 2.0: 'if the type of the connector differs from the type of the underlying FMU variable
    this constitutes an error' (SystemStructureDescription.xsd, a connector's type)."""
    fmu, ss = need(REF / "Feedthrough.fmu"), need(REF / "StateSpace.fmu")
    path, ssd = write_ssp2(tmp_path / "T.ssp", [("f", fmu)], {"f": [("Int8_output", "output", "Int16", ())]}, [], {})
    valid(ssd)
    r = cli("run", path, "--stop-time", "0.1", "--step", "0.1", "--no-progress")
    assert r.returncode == 1 and "connector 'Int8_output' is declared Int16 in the SSD, and its variable is Int8" in r.stderr, r.stderr
    path, ssd = write_ssp2(tmp_path / "D.ssp", [("s", ss)], {"s": [("y", "output", "Float64", (2,))]}, [], {})
    valid(ssd)
    r = cli("run", path, "--stop-time", "0.1", "--step", "0.1", "--no-progress")
    assert r.returncode == 1 and "connector 'y' is declared Float64[2] in the SSD, and its variable is Float64[3]" in r.stderr, r.stderr
    # SSP 1.0's Real for a Float64, and every type of the writer's files, are accepted.
    path, _ = write_ssp2(tmp_path / "R.ssp", [("f", fmu)], {"f": [("Float64_continuous_output", "output", "Real", ())]}, [], {})
    assert cli("run", path, "--stop-time", "0.1", "--step", "0.1", "--no-progress").returncode == 0
