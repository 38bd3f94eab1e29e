"""Issue 25: every FMI 3.0 variable type. The Reference-FMUs' Feedthrough written with rustfmu
(reference-fmus/feedthrough): every input set and read back through its output with
the type's own getter and setter, at the type's extremes, in fmpy's FMI 3.0 Co-Simulation and
Model Exchange; a wrong type, a non-item Enumeration value and NaN refused with nothing changed;
Binary values of every size (empty, with NUL bytes, 64 KiB); the FMU state round trip with every
type; and the FMI 2.0 Feedthrough, which has FMI 2.0's types only, as the Reference-FMUs' own."""

import contextlib
import math
import shutil
import struct

import fmpy
import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Model, FMU3Slave

from conftest import fmu, fmu3

F32_MAX = struct.unpack("<f", struct.pack("<I", 0x7F7FFFFF))[0]
F32_TINY = struct.unpack("<f", struct.pack("<I", 0x00000001))[0]  # the smallest subnormal
F32_PI = struct.unpack("<f", struct.pack("<f", math.pi))[0]

# (input name, fmpy getter/setter suffix, values at the type's extremes and between)
SCALARS = [
    ("Float32_continuous_input", "Float32", [F32_PI, -F32_MAX, F32_MAX, F32_TINY, -0.0]),
    ("Float32_discrete_input", "Float32", [1.5, -F32_MAX]),
    ("Float64_continuous_input", "Float64", [math.pi, -1e308, 5e-324]),
    ("Float64_discrete_input", "Float64", [2.5, 1e308]),
    ("Int8_input", "Int8", [-128, 127, 0]),
    ("UInt8_input", "UInt8", [0, 255, 7]),
    ("Int16_input", "Int16", [-32768, 32767]),
    ("UInt16_input", "UInt16", [0, 65535]),
    ("Int32_input", "Int32", [-(2**31), 2**31 - 1]),
    ("UInt32_input", "UInt32", [0, 2**32 - 1]),
    ("Int64_input", "Int64", [-(2**63), 2**63 - 1, 2**53 + 1]),
    ("UInt64_input", "UInt64", [0, 2**64 - 1, 2**53 + 1]),
    ("Boolean_input", "Boolean", [True, False]),
    ("Enumeration_input", "Int64", [2, 1]),
]
BINARIES = [b"", b"\x00", b"a\x00b\xff", bytes(range(256)) * 256]


@pytest.fixture(scope="module")
def feedthrough3():
    path = fmu3("Feedthrough")
    md = read_model_description(path)
    unzipdir = extract(path)
    yield path, md, unzipdir
    shutil.rmtree(unzipdir, ignore_errors=True)


def vrs(md):
    return {v.name: v.valueReference for v in md.modelVariables}


def instance(md, unzipdir, interface):
    cls = FMU3Slave if interface == "cs" else FMU3Model
    inst = cls(
        guid=md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier=(md.coSimulation if interface == "cs" else md.modelExchange).modelIdentifier,
        instanceName="feedthrough",
    )
    inst.instantiate()
    inst.enterInitializationMode(startTime=0.0)
    inst.exitInitializationMode()
    return inst


@contextlib.contextmanager
def initialized(feedthrough, interface):
    """The Feedthrough of the fixture instantiated for `interface` ("cs" or "me") and initialized,
    with its value references by name; terminated and freed when the block ends."""
    _, md, unzipdir = feedthrough
    inst = instance(md, unzipdir, interface)
    try:
        yield inst, vrs(md)
    finally:
        inst.terminate()
        inst.freeInstance()


def test_the_fmi3_description_has_every_type_as_the_reference_fmus():
    md = read_model_description(fmu3("Feedthrough"), validate=True)
    types = {v.name: v.type for v in md.modelVariables}
    assert types["time"] == "Float64"
    for name, ty in [
        ("Float32_continuous_input", "Float32"),
        ("Int8_input", "Int8"),
        ("UInt8_input", "UInt8"),
        ("Int16_input", "Int16"),
        ("UInt16_input", "UInt16"),
        ("Int32_input", "Int32"),
        ("UInt32_input", "UInt32"),
        ("Int64_input", "Int64"),
        ("UInt64_input", "UInt64"),
        ("Boolean_input", "Boolean"),
        ("String_input", "String"),
        ("String_output", "String"),
        ("Binary_input", "Binary"),
        ("Enumeration_input", "Enumeration"),
    ]:
        assert types[name] == ty, name
    # value references as the Reference-FMUs' (v0.0.41, whose String_input and String_output
    # replaced the String_parameter of before and moved Binary and Enumeration by one)
    vr = vrs(md)
    assert [vr["Float32_continuous_input"], vr["Int8_input"], vr["UInt64_output"], vr["String_input"],
            vr["String_output"], vr["Binary_input"], vr["Enumeration_output"]] == [1, 11, 26, 29, 30, 31, 34]
    by_name = {v.name: v for v in md.modelVariables}
    assert (by_name["String_input"].causality, by_name["String_input"].variability, by_name["String_input"].start) == (
        "input", "discrete", "Set me!")
    assert (by_name["String_output"].causality, by_name["String_output"].variability) == ("output", "discrete")
    out = next(u for u in md.outputs if u.variable.name == "String_output")
    assert [d.name for d in out.dependencies] == ["String_input"]
    binary = next(v for v in md.modelVariables if v.name == "Binary_input")
    assert binary.start in (b"foo", "666f6f")


@pytest.mark.parametrize("interface", ["cs", "me"])
def test_every_type_goes_through_at_its_extremes(feedthrough3, interface):
    # (Model Exchange leaves initialization in Event Mode, where discrete inputs are set.)
    with initialized(feedthrough3, interface) as (inst, vr):
        for name, ty, values in SCALARS:
            out = name.replace("input", "output")
            for x in values:
                getattr(inst, f"set{ty}")([vr[name]], [x])
                got_in = getattr(inst, f"get{ty}")([vr[name]])[0]
                got_out = getattr(inst, f"get{ty}")([vr[out]])[0]
                if isinstance(x, float):
                    # bit for bit, the sign of zero included
                    assert struct.pack("<d", got_in) == struct.pack("<d", x), (name, x, got_in)
                    assert struct.pack("<d", got_out) == struct.pack("<d", x), (out, x, got_out)
                else:
                    assert got_in == x and got_out == x, (name, x, got_in, got_out)
        for b in BINARIES:
            inst.setBinary([vr["Binary_input"]], [b])
            assert inst.getBinary([vr["Binary_input"], vr["Binary_output"]]) == [b, b]
        # several values of several variables in one call
        inst.setUInt8([vr["UInt8_input"]], [9])
        assert inst.getUInt8([vr["UInt8_input"], vr["UInt8_output"]]) == [9, 9]
        # Int64 and Enumeration in one fmi3GetInt64
        inst.setInt64([vr["Int64_input"], vr["Enumeration_input"]], [-5, 2])
        assert inst.getInt64([vr["Int64_output"], vr["Enumeration_output"]]) == [-5, 2]
        # the String output follows its input (as the Reference's calculateValues)
        assert inst.getString([vr["String_input"], vr["String_output"]]) == ["Set me!", "Set me!"]
        for text in ["", "héllo, wörld", "x" * 10_000, "Set me!"]:
            inst.setString([vr["String_input"]], [text])
            assert inst.getString([vr["String_input"], vr["String_output"]]) == [text, text]


def test_refusals_change_nothing(feedthrough3):
    with initialized(feedthrough3, "cs") as (inst, vr):
        inst.setInt16([vr["Int16_input"]], [12])
        inst.setFloat32([vr["Float32_continuous_input"]], [0.5])
        inst.setInt64([vr["Enumeration_input"]], [2])
        refused = [
            # a variable through another type's function
            lambda: inst.setInt8([vr["Int16_input"]], [1]),
            lambda: inst.getInt32([vr["UInt32_input"]]),
            lambda: inst.getFloat64([vr["Float32_continuous_input"]]),
            lambda: inst.getInt32([vr["Enumeration_input"]]),
            lambda: inst.getBinary([vr["String_input"]]),
            lambda: inst.setString([vr["String_output"]], ["x"]),
            # not finite
            lambda: inst.setFloat32([vr["Float32_continuous_input"]], [float("nan")]),
            lambda: inst.setFloat32([vr["Float32_continuous_input"], vr["Float32_discrete_input"]], [1.0, float("inf")]),
            # no item of the enumeration, and all or nothing with a good value before it
            lambda: inst.setInt64([vr["Int64_input"], vr["Enumeration_input"]], [3, 3]),
            # an output is not set
            lambda: inst.setInt16([vr["Int16_output"]], [1]),
            lambda: inst.setBinary([vr["Binary_output"]], [b"x"]),
        ]
        before = inst.getFMUState()

        def unchanged():
            assert inst.getInt16([vr["Int16_output"]]) == [12]
            assert inst.getFloat32([vr["Float32_continuous_output"], vr["Float32_discrete_input"]]) == [0.5, 0.0]
            assert inst.getInt64([vr["Int64_input"], vr["Enumeration_output"]]) == [0, 2]

        for call in refused:
            with pytest.raises(FMICallException):
                call()
            # FMI 3.0: after fmi3Error the instance is Terminated, where values can be read,
            # and the FMU state taken before brings it back.
            unchanged()
            inst.setFMUState(before)
        unchanged()
        inst.freeFMUState(before)


def test_the_fmu_state_holds_every_type(feedthrough3):
    with initialized(feedthrough3, "cs") as (inst, vr):
        inst.setUInt64([vr["UInt64_input"]], [2**64 - 2])
        inst.setFloat32([vr["Float32_discrete_input"]], [F32_PI])
        inst.setBinary([vr["Binary_input"]], [b"\x01\x02\x00\x03"])
        inst.setInt64([vr["Enumeration_input"]], [2])
        inst.setString([vr["String_input"]], ["kept"])
        state = inst.getFMUState()
        serialized = inst.serializeFMUState(state)
        inst.setUInt64([vr["UInt64_input"]], [1])
        inst.setFloat32([vr["Float32_discrete_input"]], [0.0])
        inst.setBinary([vr["Binary_input"]], [b""])
        inst.setInt64([vr["Enumeration_input"]], [1])
        inst.setString([vr["String_input"]], ["changed"])
        inst.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.1)
        for restore in (lambda: inst.setFMUState(state), lambda: inst.setFMUState(inst.deserializeFMUState(serialized))):
            restore()
            assert inst.getUInt64([vr["UInt64_output"]]) == [2**64 - 2]
            assert inst.getFloat32([vr["Float32_discrete_output"]]) == [F32_PI]
            assert inst.getBinary([vr["Binary_output"]]) == [b"\x01\x02\x00\x03"]
            assert inst.getInt64([vr["Enumeration_output"]]) == [2]
            assert inst.getString([vr["String_output"]]) == ["kept"]
        inst.freeFMUState(state)


def test_fmpy_simulates_both_versions_with_start_values_of_every_type():
    r3 = fmpy.simulate_fmu(
        fmu3("Feedthrough"),
        start_values={"Int8_input": -3, "UInt64_input": 2**64 - 1, "Float32_continuous_input": 0.25, "Enumeration_input": 2},
        output=["Int8_output", "UInt64_output", "Float32_continuous_output", "Enumeration_output"],
    )
    assert list(r3["Int8_output"][[0, -1]]) == [-3, -3]
    assert int(r3["UInt64_output"][-1]) == 2**64 - 1
    assert np.all(r3["Float32_continuous_output"] == 0.25)
    assert np.all(r3["Enumeration_output"] == 2)
    r2 = fmpy.simulate_fmu(
        fmu("Feedthrough"),
        start_values={"Int32_input": 7, "Float64_continuous_input": 1.5, "Boolean_input": True},
        output=["Int32_output", "Float64_continuous_output", "Boolean_output"],
    )
    assert np.all(r2["Int32_output"] == 7) and np.all(r2["Float64_continuous_output"] == 1.5)
    assert np.all(r2["Boolean_output"])


def test_the_fmi2_feedthrough_has_the_fmi2_types_only_and_refuses_the_others():
    path = fmu("Feedthrough")
    md = read_model_description(path, validate=True)
    names = [v.name for v in md.modelVariables]
    assert names == [
        "Float64_fixed_parameter", "Float64_tunable_parameter", "Float64_continuous_input",
        "Float64_continuous_output", "Float64_discrete_input", "Float64_discrete_output",
        "Int32_input", "Int32_output", "Boolean_input", "Boolean_output", "String_input", "String_output",
        "Enumeration_input", "Enumeration_output",
    ]
    unzipdir = extract(path)
    try:
        inst = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier="Feedthrough", instanceName="f2")
        inst.instantiate()
        inst.enterInitializationMode()
        inst.exitInitializationMode()
        inst.setInteger([19, 33], [-4, 2])
        assert inst.getInteger([20, 34]) == [-4, 2]
        # String_input (29) and String_output (30), as the Reference-FMUs' v0.0.41
        # (fmpy's FMI 2.0 getString answers bytes)
        assert inst.getString([29, 30]) == [b"Set me!", b"Set me!"]
        inst.setString([29], ["abc"])
        assert inst.getString([30]) == [b"abc"]
        # vr 1 is the Float32 input of the FMI 3.0 description only
        with pytest.raises(FMICallException):
            inst.getReal([1])
        inst.terminate()
        inst.freeInstance()
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)


def variable_dependencies(inst, vr):
    """fmpy's FMU3.getVariableDependencies, whose getNumberOfVariableDependencies passes the
    type c_size_t to byref() instead of an instance (fmpy 0.3.32): the same two calls."""
    from ctypes import byref, c_size_t
    from fmpy.fmi3 import fmi3DependencyKind, fmi3ValueReference

    n = c_size_t()
    inst.fmi3GetNumberOfVariableDependencies(inst.component, fmi3ValueReference(vr), byref(n))
    n = n.value
    arrays = ((c_size_t * n)(), (fmi3ValueReference * n)(), (c_size_t * n)(), (fmi3DependencyKind * n)())
    inst.fmi3GetVariableDependencies(inst.component, fmi3ValueReference(vr), *arrays, n)
    return tuple(list(a) for a in arrays)


@pytest.mark.parametrize("name", ["Feedthrough", "Controller", "Pendulum", "DCMotor", "BouncingBall"])
def test_variable_dependencies_in_fmpy_equal_the_model_structure(name):
    """fmpy's getVariableDependencies after initialization: every <Output> and
    <ContinuousStateDerivative> answers the value references of its `dependencies` (every input
    and state where the attribute is left out)."""
    path = fmu3(name)
    md = read_model_description(path)
    unzipdir = extract(path)
    try:
        inst = instance(md, unzipdir, "cs")
        by_vr = {v.valueReference: v for v in md.modelVariables}
        knowns = {v.valueReference for v in md.modelVariables if v.causality == "input"} | {
            d.variable.derivative.valueReference for d in md.derivatives
        }
        n = 0
        for u in md.outputs + md.derivatives:
            vr = u.variable.valueReference
            want = {d.valueReference for d in u.dependencies} if u.dependencies is not None else knowns
            _, independents, _, kinds = variable_dependencies(inst, vr)
            assert set(independents) == want, (by_vr[vr].name, list(independents), want)
            assert all(k == 5 for k in kinds)  # fmi3Dependent
            n += 1
        assert n > 0
        inst.terminate()
        inst.freeInstance()
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)


@pytest.mark.parametrize(
    "name, terminals",
    [
        ("Pendulum", {"joint1": {"phi": ("alpha1", "signal"), "w": ("omega1", "signal"), "tau": ("M1", "inflow")},
                      "joint2": {"phi": ("alpha2", "signal"), "w": ("omega2", "signal"), "tau": ("M2", "inflow")}}),
        ("DCMotor", {"shaft": {"w": ("omega", "signal"), "tau": ("tau", "outflow")}}),
    ],
)
def test_terminals_follow_the_schema_and_name_the_joints_and_the_shaft(name, terminals):
    """terminalsAndIcons/terminalsAndIcons.xml of the FMI 3.0 FMUs: valid against the FMI 3.0
    schema fmpy ships (fmi3TerminalsAndIcons.xsd), every member an existing variable, the
    flanges' members as declared; the FMI 2.0 FMUs carry none."""
    import pathlib
    import zipfile

    from lxml import etree

    path = fmu3(name)
    with zipfile.ZipFile(path) as z:
        text = z.read("terminalsAndIcons/terminalsAndIcons.xml")
    schema_dir = pathlib.Path(fmpy.__file__).parent / "schema" / "fmi3"
    schema = etree.XMLSchema(etree.parse(str(schema_dir / "fmi3TerminalsAndIcons.xsd")))
    doc = etree.fromstring(text)
    assert schema.validate(doc), schema.error_log
    variables = {v.name for v in read_model_description(path).modelVariables}
    got = {}
    for t in doc.iter("Terminal"):
        assert t.get("matchingRule") == "plug"
        assert t.get("terminalKind").startswith("org.modelica.Modelica.Mechanics.Rotational.Interfaces.Flange_")
        got[t.get("name")] = {
            m.get("memberName"): (m.get("variableName"), m.get("variableKind")) for m in t.iter("TerminalMemberVariable")
        }
        assert all(v in variables for v, _ in got[t.get("name")].values())
    assert got == terminals
    with zipfile.ZipFile(fmu(name)) as z:
        assert not any(n.startswith("terminalsAndIcons/") for n in z.namelist())


def test_the_controllers_gain_is_a_2_by_4_array_equal_to_its_scalars():
    """The Controller's K (vr 110): <Dimension>s 2 and 4 in fmpy's reading of the 3.0
    description; its 8 values, read with nValues = 8, row-major, equal K11 .. K24; with nValues
    = 7 the read is refused. The FMI 2.0 Controller lists it as the scalars K[1,1] .. K[2,4]
    (the standard's structured naming, value references 110 .. 117), equal to K11 .. K24 too."""
    path = fmu3("Controller")
    md = read_model_description(path, validate=True)
    k = next(v for v in md.modelVariables if v.name == "K")
    assert [int(d.start) for d in k.dimensions] == [2, 4]
    assert k.causality == "calculatedParameter"
    unzipdir = extract(path)
    try:
        inst = instance(md, unzipdir, "cs")
        vr = vrs(md)
        scalars = inst.getFloat64([vr[f"K{i}{j}"] for i in (1, 2) for j in (1, 2, 3, 4)])
        assert inst.getFloat64([110], nValues=8) == scalars
        assert abs(scalars[7] - 0.9957) < 5e-4  # the paper's K(2,4)
        with pytest.raises(FMICallException):
            inst.getFloat64([110], nValues=7)
        inst.freeInstance()
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)

    md2 = read_model_description(fmu("Controller"), validate=True)
    assert md2.variableNamingConvention == "structured"
    elements = [v for v in md2.modelVariables if v.name.startswith("K[")]
    assert [(v.name, v.valueReference) for v in elements] == [
        (f"K[{i},{j}]", 110 + 4 * (i - 1) + (j - 1)) for i in (1, 2) for j in (1, 2, 3, 4)
    ]
    assert all(v.causality == "calculatedParameter" and v.type == "Real" for v in elements)
    unzipdir = extract(fmu("Controller"))
    try:
        slave = FMU2Slave(guid=md2.guid, unzipDirectory=unzipdir,
                          modelIdentifier=md2.coSimulation.modelIdentifier, instanceName="k2")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        vr2 = {v.name: v.valueReference for v in md2.modelVariables}
        scalars2 = slave.getReal([vr2[f"K{i}{j}"] for i in (1, 2) for j in (1, 2, 3, 4)])
        assert slave.getReal([v.valueReference for v in elements]) == scalars2 == scalars
        slave.terminate()
        slave.freeInstance()
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)
