"""Every FMI 3.0 type and array in the native runner (issue 54, items 1 and 4): the C Reference
FMUs' Feedthrough (every type) and StateSpace (arrays sized by structural parameters), alone and
connected to this project's re-makes, against fmusim (the Reference FMUs' own simulator, which
nobody here wrote) on the same FMUs with the same start values and inputs; connections of another
type or size refused when the system is built, naming both ends."""

import csv
import pathlib
import subprocess
import zipfile

import numpy as np
import pytest
from conftest import FMU_DIR, ROOT
from test_runner import cli

INDEPENDENT = ROOT.parent / "shared" / "independent"
FMUSIM = INDEPENDENT / "bin" / "fmusim"
REF = INDEPENDENT / "reference-fmus" / "3.0"

# Feedthrough's numeric types: each <T>_input feeds <T>_output.
NUMERIC = ["Float32_continuous", "Float64_continuous", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64",
           "UInt64", "Boolean", "Enumeration"]
# A value of each, at the edge of its range where it has one.
VALUES = {"Float32_continuous": "0.1", "Float64_continuous": "-2.5", "Int8": "-128", "UInt8": "255", "Int16": "-32768",
          "UInt16": "65535", "Int32": "-2147483648", "UInt32": "4294967295", "Int64": "-9007199254740992",
          "UInt64": "9007199254740993", "Boolean": "true", "Enumeration": "2"}


def need(path: pathlib.Path) -> str:
    if not path.exists():
        pytest.skip(f"{path} is not here (../shared/independent holds what nobody here wrote)")
    return str(path)


def ours(name: str) -> str:
    path = FMU_DIR / "fmi3" / f"{name}.fmu"
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo run --release -p fmu-build` first")
    return str(path)


def write_ssp(out, components, connections=(), parameters=()):
    """An SSP 1.0 file of `components` [(name, fmu path)], `connections` [(a, out, b, in)] and
    `parameters` [(component, variable, ssv type, value)]."""
    elements = []
    for name, path in components:
        ps = "".join(f'<ssv:Parameter name="{v}"><ssv:{t} value="{x}"/></ssv:Parameter>'
                     for c, v, t, x in parameters if c == name)
        binding = (f'<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="1.0" '
                   f'name="p"><ssv:Parameters>{ps}</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues>'
                   f'</ssd:ParameterBinding></ssd:ParameterBindings>') if ps else ""
        elements.append(f'<ssd:Component name="{name}" source="resources/{name}.fmu" '
                        f'type="application/x-fmu-sharedlibrary">{binding}</ssd:Component>')
    links = "".join(f'<ssd:Connection startElement="{a}" startConnector="{b}" endElement="{c}" endConnector="{d}"/>'
                    for a, b, c, d in connections)
    ssd = ('<?xml version="1.0" encoding="UTF-8"?>\n'
           '<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
           'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
           'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="S">'
           f'<ssd:System name="S"><ssd:Elements>{"".join(elements)}</ssd:Elements>'
           f'<ssd:Connections>{links}</ssd:Connections></ssd:System></ssd:SystemStructureDescription>')
    with zipfile.ZipFile(out, "w") as z:
        z.writestr("SystemStructure.ssd", ssd)
        for name, path in components:
            z.write(path, f"resources/{name}.fmu")
    return str(out)


def read_csv(path) -> dict:
    """Columns by name; a cell of several numbers (fmusim's array) split into its elements."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    out = {}
    for j, name in enumerate(rows[0]):
        cells = [r[j] for r in rows[1:]]
        try:
            out[name] = np.array([[float(x) for x in c.split()] for c in cells])
        except ValueError:
            out[name] = cells
        if not isinstance(out[name], list) and out[name].shape[1] == 1:
            out[name] = out[name][:, 0]
    return out


def runner(tmp_path, ssp, stop, step, *args) -> dict:
    out = tmp_path / "runner.csv"
    r = cli("run", ssp, "--stop-time", stop, "--step", step, "--no-progress", "--output", out, *args)
    assert r.returncode == 0, r.stderr
    return read_csv(out)


def fmusim(tmp_path, fmu, stop, step, *args) -> dict:
    out = tmp_path / "fmusim.csv"
    r = subprocess.run([need(FMUSIM), "--interface-type", "cs", "--stop-time", str(stop), "--output-interval", str(step),
                        "--output-file", str(out), *map(str, args), fmu], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    return read_csv(out)


def same(t: str, got, ref) -> bool:
    """Equal values; a Float32 compared as a Float32 (fmusim prints it to 7 digits, the runner
    records its exact double)."""
    ref = np.asarray(ref, dtype=float)
    if t.startswith("Float32"):
        return np.array_equal(np.float32(got), np.float32(ref))
    return np.array_equal(got, ref)


def as_number(text: str) -> float:
    return {"true": 1.0, "false": 0.0}[text] if text in ("true", "false") else float(text)


def test_every_feedthrough_type_set_by_the_run_equals_fmusim(tmp_path):
    """The run's overrides of each type (--set, at the edges of the integer ranges), each output
    recorded (an Int64 or UInt64 as the nearest double: the row is of numbers), against fmusim's
    --start-value on the Reference Feedthrough."""
    fmu = need(REF / "Feedthrough.fmu")
    ssp = write_ssp(tmp_path / "F.ssp", [("f", fmu)])
    sets = [a for t in NUMERIC for a in ("--set", f"f.{t}_input={VALUES[t]}")]
    records = [a for t in NUMERIC for a in ("--record", f"f.{t}_output")]
    got = runner(tmp_path, ssp, 0.2, 0.1, *sets, *records)
    starts = [a for t in NUMERIC for a in ("--start-value", f"{t}_input", VALUES[t])]
    ref = fmusim(tmp_path, fmu, 0.2, 0.1, *starts)
    for t in NUMERIC:
        assert same(t, got[f"f.{t}_output"], ref[f"{t}_output"]), (t, got[f"f.{t}_output"], ref[f"{t}_output"])
        if t not in ("Float32_continuous", "UInt64", "Int64"):
            assert got[f"f.{t}_output"][0] == as_number(VALUES[t]), t


def test_ssp_parameter_values_of_each_type_equal_fmusim(tmp_path):
    """SSP 1.0 values (ssv:Real into Float32 and Float64, ssv:Integer into every integer type and
    the Enumeration, ssv:Boolean, ssv:String) bound to the Reference Feedthrough's inputs."""
    fmu = need(REF / "Feedthrough.fmu")
    ssv = {"Float32_continuous": "Real", "Float64_continuous": "Real", "Boolean": "Boolean"}
    params = [("f", f"{t}_input", ssv.get(t, "Integer"), VALUES[t]) for t in NUMERIC]
    params.append(("f", "String_input", "String", "typed"))
    ssp = write_ssp(tmp_path / "F.ssp", [("f", fmu)], parameters=params)
    got = runner(tmp_path, ssp, 0.1, 0.1, *[a for t in NUMERIC for a in ("--record", f"f.{t}_output")])
    ref = fmusim(tmp_path, fmu, 0.1, 0.1, *[a for t in NUMERIC for a in ("--start-value", f"{t}_input", VALUES[t])])
    for t in NUMERIC:
        assert same(t, got[f"f.{t}_output"], ref[f"{t}_output"]), t
    # A value outside its type's range is refused before any call, naming the variable.
    bad = write_ssp(tmp_path / "B.ssp", [("f", fmu)], parameters=[("f", "UInt8_input", "Integer", "256")])
    r = cli("run", bad, "--stop-time", "0.1", "--step", "0.1", "--no-progress")
    assert r.returncode == 1 and "UInt8_input (UInt8)" in r.stderr and "out of the UInt8 range" in r.stderr, r.stderr


def test_the_reference_feedthrough_drives_ours_through_every_type(tmp_path):
    """Every output of the Reference Feedthrough (C) connected to the same input of this project's
    Feedthrough (Rust), String and Binary included: ours passes on what fmusim computes for the
    Reference one alone; a String and a Binary set on the first come out of the second."""
    ref_fmu = need(REF / "Feedthrough.fmu")
    ssp = write_ssp(tmp_path / "FF.ssp", [("ref", ref_fmu), ("ours", ours("Feedthrough"))],
                    [("ref", f"{t}_output", "ours", f"{t}_input") for t in NUMERIC + ["String", "Binary"]])
    sets = [a for t in NUMERIC for a in ("--set", f"ref.{t}_input={VALUES[t]}")]
    got = runner(tmp_path, ssp, 0.3, 0.1, *sets, *[a for t in NUMERIC for a in ("--record", f"ours.{t}_output")])
    ref = fmusim(tmp_path, ref_fmu, 0.3, 0.1, *[a for t in NUMERIC for a in ("--start-value", f"{t}_input", VALUES[t])])
    for t in NUMERIC:
        assert same(t, got[f"ours.{t}_output"], ref[f"{t}_output"]), t
    # String and Binary cannot be recorded (the rows are numbers): refused, naming why.
    r = cli("run", ssp, "--stop-time", "0.1", "--step", "0.1", "--no-progress", "--record", "ours.Binary_output")
    assert r.returncode == 1 and "ours.Binary_output is a Binary: it cannot be recorded" in r.stderr, r.stderr


def test_the_reference_statespace_arrays_equal_fmusim(tmp_path):
    """StateSpace's arrays, sized by its structural parameters (3 × 3): y recorded as y[1] .. y[3],
    u and A set by the run as space-separated elements (row-major), against fmusim."""
    fmu = need(REF / "StateSpace.fmu")
    ssp = write_ssp(tmp_path / "S.ssp", [("s", fmu)])
    u, a = "0.5 -1 2", "-1 0 0 0 -2 0 0 0 -3"
    got = runner(tmp_path, ssp, 1.0, 0.25, "--set", f"s.u={u}", "--set", f"s.A={a}")
    ref = fmusim(tmp_path, fmu, 1.0, 0.25, "--start-value", "u", u, "--start-value", "A", a)
    assert [k for k in got if k != "time"] == ["s.y[1]", "s.y[2]", "s.y[3]"]
    y = np.column_stack([got[f"s.y[{i}]"] for i in (1, 2, 3)])
    assert np.max(np.abs(y - ref["y"])) <= 1e-15, (y, ref["y"])
    assert np.array_equal(y[0], [0.5, -1.0, 2.0])
    # The wrong number of elements, and a structural parameter, are refused with what they are.
    r = cli("run", ssp, "--stop-time", "0.1", "--step", "0.1", "--no-progress", "--set", "s.u=1 2")
    assert r.returncode == 1 and "s.u (Float64[3])" in r.stderr and "2 value(s) given, the variable has 3" in r.stderr, r.stderr
    r = cli("run", ssp, "--stop-time", "0.1", "--step", "0.1", "--no-progress", "--set", "s.m=2")
    assert r.returncode == 1 and "a structural parameter" in r.stderr, r.stderr


def test_the_reference_statespace_drives_ours_element_wise(tmp_path):
    """The Reference StateSpace's y (Float64[3]) into our StateSpace's u: our state x equals
    fmusim's running ours alone with the Reference one's y (itself from fmusim) as its input file.
    (The state, not y: y = C x + D u feeds u through, and fmusim writes a row before it sets the
    inputs of that time, the runner after.)"""
    ref_fmu = need(REF / "StateSpace.fmu")
    ssp = write_ssp(tmp_path / "SS.ssp", [("ref", ref_fmu), ("ours", ours("StateSpace"))], [("ref", "y", "ours", "u")])
    got = runner(tmp_path, ssp, 1.0, 0.25, "--record", "ours.x", "--record", "ref.y")
    first = fmusim(tmp_path, ref_fmu, 1.0, 0.25)
    y = np.column_stack([got[f"ref.y[{i}]"] for i in (1, 2, 3)])
    assert np.max(np.abs(y - first["y"])) <= 1e-15
    inputs = tmp_path / "u.csv"
    inputs.write_text('"time","u"\n' + "".join(
        f"{float(t)!r},{' '.join(repr(float(x)) for x in row)}\n" for t, row in zip(first["time"], first["y"])))
    ref = fmusim(tmp_path, ours("StateSpace"), 1.0, 0.25, "--input-file", inputs, "--output-variable", "x")
    x = np.column_stack([got[f"ours.x[{i}]"] for i in (1, 2, 3)])
    assert np.max(np.abs(x - ref["x"])) <= 1e-12 * np.max(np.abs(ref["x"])), (x, ref["x"])
    assert np.max(np.abs(x[-1])) > 1.0


def test_a_connection_of_another_type_or_size_is_refused_naming_both_ends(tmp_path):
    fmu = need(REF / "Feedthrough.fmu")
    ssp = write_ssp(tmp_path / "T.ssp", [("a", fmu), ("b", fmu)], [("a", "Int8_output", "b", "UInt8_input")])
    r = cli("run", ssp, "--stop-time", "0.1", "--step", "0.1", "--no-progress")
    assert r.returncode == 1, r.stderr
    assert "connection a.Int8_output -> b.UInt8_input: a.Int8_output is Int8 and b.UInt8_input is UInt8" in r.stderr, r.stderr
    # A StateSpace whose inputs are 2 (its structural parameter m's start edited to 2) fed the
    # Reference one's 3 outputs.
    small = tmp_path / "StateSpace2.fmu"
    with zipfile.ZipFile(need(REF / "StateSpace.fmu")) as src, zipfile.ZipFile(small, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                edited = text.replace('name="m" valueReference="1" description="Number of inputs" '
                                      'causality="structuralParameter" variability="tunable" start="3"',
                                      'name="m" valueReference="1" description="Number of inputs" '
                                      'causality="structuralParameter" variability="tunable" start="2"')
                assert edited != text
                data = edited.replace('start="1 2 3">', 'start="1 2">').encode()
            dst.writestr(item, data)
    ssp = write_ssp(tmp_path / "Z.ssp", [("big", str(REF / "StateSpace.fmu")), ("small", str(small))],
                    [("big", "y", "small", "u")])
    r = cli("run", ssp, "--stop-time", "0.1", "--step", "0.1", "--no-progress")
    assert r.returncode == 1, r.stderr
    assert "connection big.y -> small.u: big.y is Float64[3] and small.u is Float64[2]" in r.stderr, r.stderr
    # An array into a scalar of its type.
    ssp = write_ssp(tmp_path / "S.ssp", [("s", str(REF / "StateSpace.fmu")), ("f", fmu)],
                    [("s", "y", "f", "Float64_continuous_input")])
    r = cli("run", ssp, "--stop-time", "0.1", "--step", "0.1", "--no-progress")
    assert "s.y is Float64[3] and f.Float64_continuous_input is Float64" in r.stderr, r.stderr


def test_a_cycle_of_typed_feedthrough_is_refused_as_a_loop_newton_does_not_solve(tmp_path):
    """Int8_output depends on Int8_input (Feedthrough's ModelStructure): two of them in a ring
    are an algebraic loop of Int8 values, which Newton's method (Float64 unknowns) cannot solve."""
    fmu = need(REF / "Feedthrough.fmu")
    ssp = write_ssp(tmp_path / "L.ssp", [("a", fmu), ("b", fmu)],
                    [("a", "Int8_output", "b", "Int8_input"), ("b", "Int8_output", "a", "Int8_input")])
    r = cli("run", ssp, "--stop-time", "0.1", "--step", "0.1", "--no-progress")
    assert r.returncode == 1, r.stderr
    assert "(Int8) closes an algebraic loop" in r.stderr and "loops of Float64 values only" in r.stderr, r.stderr


@pytest.mark.skipif(not pathlib.Path("/dev/shm").is_dir(), reason="isolation runs on Linux")
def test_typed_values_cross_to_isolated_components_unchanged(tmp_path):
    """Every component in a child process (--isolate), or the whole system in one: the typed
    connections, overrides and records give the rows of the run in the runner's process."""
    ref = need(REF / "Feedthrough.fmu")
    ssp = write_ssp(tmp_path / "M.ssp", [("a", ref), ("b", ours("Feedthrough")), ("s", need(REF / "StateSpace.fmu")),
                                         ("o", ours("StateSpace"))],
                    [("a", f"{t}_output", "b", f"{t}_input") for t in NUMERIC + ["String", "Binary"]] + [("s", "y", "o", "u")])
    args = [a for t in NUMERIC for a in ("--set", f"a.{t}_input={VALUES[t]}")]
    args += ["--set", "s.u=3 2 1", "--set", "a.String_input=hi", "--set", "a.Binary_input=00ff",
             "--record", "o.y", "--record", "o.x", *[a for t in NUMERIC for a in ("--record", f"b.{t}_output")]]
    here = runner(tmp_path, ssp, 0.5, 0.1, *args)
    for isolate in (["--isolate"], ["--isolate", "system"]):
        there = runner(tmp_path, ssp, 0.5, 0.1, *isolate, *args)
        assert list(there) == list(here)
        for k in here:
            assert np.array_equal(there[k], here[k]), (isolate, k)
    assert here["b.Int8_output"][-1] == -128 and here["o.y[1]"][0] == 3.0


def test_the_python_module_takes_arrays_as_sequences_and_records_their_elements(tmp_path):
    """The module's start values of an array: a list or a numpy array of any shape (row-major), a
    numpy Boolean as the runner's true; the elements come back as columns y[1] .. y[3], equal
    to fmusim's."""
    import rustfmu_runner

    fmu = need(REF / "StateSpace.fmu")
    ssp = write_ssp(tmp_path / "S.ssp", [("s", fmu)])
    a = np.diag([-1.0, -2.0, -3.0])
    r = rustfmu_runner.System(ssp).run(1.0, 0.25, start={"s.u": [0.5, -1, 2], "s.A": a}, record=["s.y"])
    assert [k for k in r if k != "time"] == ["s.y[1]", "s.y[2]", "s.y[3]"]
    ref = fmusim(tmp_path, fmu, 1.0, 0.25, "--start-value", "u", "0.5 -1 2", "--start-value", "A",
                 " ".join(repr(float(x)) for x in a.flatten()))
    y = np.column_stack([r[f"s.y[{i}]"] for i in (1, 2, 3)])
    assert np.max(np.abs(y - ref["y"])) <= 1e-15, (y, ref["y"])
    f = write_ssp(tmp_path / "F.ssp", [("f", need(REF / "Feedthrough.fmu"))])
    r = rustfmu_runner.System(f).run(0.1, 0.1, start={"f.Boolean_input": np.True_, "f.UInt16_input": np.uint16(7)},
                                     record=["f.Boolean_output", "f.UInt16_output"])
    assert list(r["f.Boolean_output"]) == [1.0, 1.0] and list(r["f.UInt16_output"]) == [7.0, 7.0]


def test_the_reference_statespace_as_model_exchange_integrates_its_array_state(tmp_path):
    """StateSpace run as model exchange (the SSD's implementation="ModelExchange"; the runner
    integrates it): its three continuous states are the elements of one array derivative, der(x)
    of Float64[3]. With A = diag(-1, -2, -3), B = C = D = I and a constant u, y = x + u with
    x_i = u_i (1 - exp(a_i t)) / -a_i, the solution written here."""
    fmu = need(REF / "StateSpace.fmu")
    ssp = pathlib.Path(write_ssp(tmp_path / "S.ssp", [("s", fmu)]))
    with zipfile.ZipFile(ssp) as z:
        ssd, data = z.read("SystemStructure.ssd").decode(), z.read("resources/s.fmu")
    me = tmp_path / "ME.ssp"
    with zipfile.ZipFile(me, "w") as z:
        z.writestr("SystemStructure.ssd", ssd.replace('type="application/x-fmu-sharedlibrary"',
                                                      'type="application/x-fmu-sharedlibrary" implementation="ModelExchange"'))
        z.writestr("resources/s.fmu", data)
    u, a = np.array([0.5, -1.0, 2.0]), np.array([-1.0, -2.0, -3.0])
    got = runner(tmp_path, me, 1.0, 0.25, "--set", f"s.u={' '.join(map(str, u))}",
                 "--set", f"s.A={' '.join(map(str, np.diag(a).flatten()))}")
    t = got["time"][:, None]
    exact = u * (1 - np.exp(a * t)) / -a + u
    y = np.column_stack([got[f"s.y[{i}]"] for i in (1, 2, 3)])
    assert np.max(np.abs(y - exact)) <= 1e-6, (y, exact)
    assert np.max(np.abs(y[-1] - u)) > 0.3  # the states moved
