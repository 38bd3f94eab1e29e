"""The BouncingBall's alias `h_ft` of `h`, shown in feet, as the Reference-FMUs v0.0.41 declare it
(issue 52, item 7): the FMI 3.0 `<Alias>` and `<DisplayUnit>` read by fmpy as the Reference's are,
the FMI 2.0 alias a `<ScalarVariable>` of h's value reference, both files valid for fmpy, and the
alias's value the value of h in a simulation of each version."""

import pathlib

import fmpy
import fmpy.validation
import numpy as np
import pytest

from conftest import ROOT, fmu, fmu3

REFERENCE = ROOT.parent / "shared" / "independent" / "reference-fmus"


def reference(version: str) -> str:
    path = REFERENCE / version / "BouncingBall.fmu"
    if not path.exists():
        pytest.skip(f"{path} is not there (the independent material is outside the checkout)")
    return str(path)


def variable(md, name):
    found = [v for v in md.modelVariables if v.name == name]
    assert found, f"no variable '{name}' in {[v.name for v in md.modelVariables]}"
    return found[0]


def display_units(md, unit):
    units = {u.name: u for u in md.unitDefinitions}
    assert unit in units, f"no unit '{unit}' in {sorted(units)}"
    return {d.name: (d.factor, d.offset) for d in units[unit].displayUnits}


def test_the_fmi3_alias_and_its_display_unit_are_the_references():
    ours, theirs = (fmpy.read_model_description(p) for p in (fmu3("BouncingBall"), reference("3.0")))
    for md in (ours, theirs):
        assert md.fmiVersion == "3.0"
    h, ref_h = variable(ours, "h"), variable(theirs, "h")
    got = [(a.name, a.description, a.displayUnit) for a in h.aliases]
    want = [(a.name, a.description, a.displayUnit) for a in ref_h.aliases]
    assert want == [("h_ft", "Position in feet", "ft")], "the Reference's alias as read from its FMU"
    assert got == want, f"h's aliases: {got}, the Reference's: {want}"
    # The alias is h under another name: its value reference and unit.
    alias = variable(ours, "h_ft")
    assert (alias.valueReference, alias.unit, alias.displayUnit) == (h.valueReference, "m", "ft")
    assert display_units(ours, "m") == display_units(theirs, "m") == {"ft": (3.280839895, 0.0)}


def test_the_fmi2_alias_is_a_local_scalar_variable_of_hs_value_reference():
    md = fmpy.read_model_description(fmu("BouncingBall"))
    h, alias = variable(md, "h"), variable(md, "h_ft")
    assert alias.valueReference == h.valueReference
    assert (alias.type, alias.causality, alias.variability) == ("Real", "local", h.variability)
    assert (alias.unit, alias.displayUnit, alias.start) == ("m", "ft", None)
    assert alias.description == "Position in feet"
    assert display_units(md, "m") == {"ft": (3.280839895, 0.0)}
    # The variables before it keep their indices: the alias comes after every declared variable.
    assert md.modelVariables[-1] is alias


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_fmpy_validates_the_description_with_the_alias(version):
    path = fmu("BouncingBall") if version == "2.0" else fmu3("BouncingBall")
    assert fmpy.validation.validate_fmu(path) == []


@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("fmi_type", ["ModelExchange", "CoSimulation"])
def test_the_alias_reads_the_value_of_h(version, fmi_type):
    # fmi2GetReal / fmi3GetFloat64 on the alias's value reference: h's value, bounce after bounce.
    path = fmu("BouncingBall") if version == "2.0" else fmu3("BouncingBall")
    result = fmpy.simulate_fmu(path, fmi_type=fmi_type, stop_time=3.0, output_interval=0.01, output=["h", "h_ft"])
    h, h_ft = result["h"], result["h_ft"]
    assert np.ptp(h) > 0.9, "the ball falls from 1 m"
    np.testing.assert_array_equal(h_ft, h)
