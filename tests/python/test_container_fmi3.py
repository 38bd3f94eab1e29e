"""FMI 3.0 container FMUs (`cargo fmu container SYSTEM.ssp --fmi-version 3|both`, issue 28): the
same binary as the FMI 2.0 container behind FMI 3.0's co-simulation API, run in fmpy's FMI 3.0
importer equal to the native runner on the SSP file and to the FMI 2.0 container, conformant
(`cargo fmu check`, fmpy's validator), refusing what it does not offer with the reason.

The containers are the ones the main job and tests/run.sh write (target/fmu/containers/fmi3/);
a missing one is made here for this machine's platform only."""

import pathlib
import re
import shutil
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from conftest import FMU_DIR
from test_container import CARGO_FMU, H, SYSTEMS, runner, ssp

import fmpy
from fmpy.fmi3 import FMU3Model, FMU3Slave
from fmpy.validation import validate_fmu


def container3(name: str):
    path = FMU_DIR / "containers" / "fmi3" / f"{name}.fmu"
    if not path.exists():
        out = FMU_DIR / "containers" / f"{name}.fmu"
        out.parent.mkdir(parents=True, exist_ok=True)
        r = subprocess.run(
            [CARGO_FMU, "fmu", "container", ssp(name), "-o", out, "--fmi-version", "both",
             "--target", "x86_64-unknown-linux-gnu"],
            capture_output=True,
            text=True,
            timeout=1800,
        )
        assert r.returncode == 0, r.stderr[-4000:]
    return path


class Slave3:
    """A container instance through fmpy's FMU3Slave."""

    def __init__(self, name, tmp_path, messages=None, logging=False, instance="container"):
        self.path = container3(name)
        self.md = fmpy.read_model_description(self.path)
        self.dir = fmpy.extract(self.path, unzipdir=tmp_path / f"{name}-{instance}")
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=instance)
        log = None
        if messages is not None:
            def log(_env, status, category, message):
                messages.append((status, category.decode(), message.decode()))
        self.fmu.instantiate(loggingOn=logging, logMessage=log)

    def outputs(self):
        return [v.name for v in self.md.modelVariables if v.causality == "output" and v.type == "Float64"]

    def run(self, stop, h, record, start=None):
        n = int(round(stop / h))
        for k, v in (start or {}).items():
            self.fmu.setFloat64([self.vr[k]], [v])
        self.fmu.enterInitializationMode(startTime=0.0, stopTime=n * h)
        self.fmu.exitInitializationMode()
        vrs = [self.vr[r] for r in record]
        rows = []
        for k in range(n + 1):
            rows.append(self.fmu.getFloat64(vrs))
            if k < n:
                event, terminate, early, last = self.fmu.doStep(k * h, h)
                assert not (event or terminate or early) and last == pytest.approx((k + 1) * h, abs=1e-15)
        return np.array(rows)

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


@pytest.mark.parametrize("name", SYSTEMS)
def test_the_fmi3_container_computes_what_the_runner_computes_on_the_ssp_file(name, tmp_path):
    """Largest difference 0, as the FMI 2.0 container: the same binary and master."""
    s = Slave3(name, tmp_path)
    record = s.outputs()
    a = s.run(2.0, H, record)
    s.free()
    b = runner(name, 2.0, H, record)
    assert a.shape == b.shape
    assert np.max(np.abs(a - b)) == 0.0
    i = record.index("pendulum.alpha1")
    assert a[0, i] == 0.1 and abs(a[-1, i]) < 0.05


@pytest.mark.parametrize("name", SYSTEMS)
def test_fmpy_simulate_fmu_runs_the_fmi3_container_as_the_fmi2_one(name):
    path = container3(name)
    md = fmpy.read_model_description(path)
    record = [v.name for v in md.modelVariables if v.causality == "output" and v.type == "Float64"]
    r3 = fmpy.simulate_fmu(str(path), stop_time=2.0, step_size=H, output_interval=H, output=record)
    b = runner(name, 2.0, H, record)
    a = np.column_stack([np.asarray(r3[x], float) for x in record])
    assert a.shape == b.shape
    assert np.max(np.abs(a - b)) <= 1e-12 * max(1.0, np.max(np.abs(b)))
    assert md.fmiVersion == "3.0" and float(md.defaultExperiment.stepSize) == H


@pytest.mark.parametrize("name", SYSTEMS)
def test_the_fmi3_container_is_valid_for_fmpy_fmutool_and_cargo_fmu_check(name):
    path = container3(name)
    assert validate_fmu(str(path)) == []
    fmutool = shutil.which("fmutool") or shutil.which("fmutool", path=str(pathlib.Path(sys.executable).parent))
    assert fmutool, "fmutool is missing: run tests/setup-env.sh"
    r = subprocess.run([fmutool, "-input", path, "-check"], capture_output=True, text=True, timeout=300)
    errors = [line for line in (r.stdout + r.stderr).splitlines() if re.match(r"^\s*(ERROR|CRITICAL)\b", line)]
    assert r.returncode == 0 and not errors and "No semantic error against the FMI-3" in r.stdout + r.stderr, r.stdout + r.stderr
    r = subprocess.run([CARGO_FMU, "fmu", "check", "--strict", "--timeout", "120", path], capture_output=True, text=True, timeout=1800)
    tail = (r.stdout + r.stderr)[-6000:]
    assert r.returncode == 0, tail
    assert re.search(r"\b0 failed\b", r.stdout + r.stderr), tail


def test_the_fmi3_variables_are_the_fmi2_ones_in_fmi3_types_with_time():
    md2 = fmpy.read_model_description(FMU_DIR / "containers" / "PendulumLQR.fmu")
    md3 = fmpy.read_model_description(container3("PendulumLQR"))
    v2 = {x.name: x for x in md2.modelVariables}
    v3 = {x.name: x for x in md3.modelVariables}
    # (A GUID of its own: it is made of the components' FMI 3.0 FMUs, the FMI 2.0 one of their
    # FMI 2.0 FMUs; test_the_fmi3_container_is_made_of_the_fmi3_components_with_aarch64_linux.)
    assert set(v3) == set(v2) | {"time"}
    kinds = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String",
             "Enumeration": "Enumeration"}
    for n, x in v2.items():
        y = v3[n]
        assert (y.valueReference, y.causality, y.variability, y.start, y.unit) == (
            x.valueReference, x.causality, x.variability, x.start, x.unit), n
        assert y.type == kinds[x.type], n
    assert v3["time"].causality == "independent" and v3["time"].valueReference == len(v2)
    assert v3["controller.mode"].declaredType.name == "ControlMode"
    assert [i.name for i in v3["controller.mode"].declaredType.items] == [
        i.name for i in v2["controller.mode"].declaredType.items]
    # The same output dependencies as the FMI 2.0 container.
    d2 = {o.variable.name: sorted(d.name for d in o.dependencies) for o in md2.outputs}
    d3 = {o.variable.name: sorted(d.name for d in o.dependencies) for o in md3.outputs}
    assert d2 == d3 and "controller.alpha1_ref" in d3["controller.M1"]


@pytest.mark.parametrize("name", SYSTEMS)
def test_the_fmi3_container_is_made_of_the_fmi3_components_with_aarch64_linux(name):
    """Issue 49: the FMI 3.0 containers the main job and tests/run.sh write carry
    binaries/aarch64-linux/, as every other FMI 3.0 FMU: `cargo fmu container
    target/fmu/<system>.ssp` makes the FMI 3.0 container of target/fmu/fmi3/<system>.ssp, the same
    system of the components' FMI 3.0 FMUs, which carry aarch64-linux (FMI 2.0 names no folder for
    it, so the FMI 2.0 container and its components have none). test_aarch64.py runs it."""
    path = FMU_DIR / "containers" / "fmi3" / f"{name}.fmu"
    assert path.exists(), f"{path} is missing: run `bash tests/run.sh` (or the main job) first"

    def folders(z, prefix=""):
        return {n[len(prefix):].split("/")[1] for n in z.namelist()
                if n.startswith(prefix + "binaries/") and not n.endswith("/")}

    with zipfile.ZipFile(path) as z:
        assert folders(z) == {"x86_64-linux", "aarch64-linux", "x86_64-windows", "x86_64-darwin", "aarch64-darwin"}
        components = sorted({n.split("/")[3] for n in z.namelist()
                             if n.startswith("resources/system/resources/") and n.split("/")[3].endswith(".fmu")})
        assert len(components) >= 2, components
        for c in components:
            inner = f"resources/system/resources/{c}/"
            assert 'fmiVersion="3.0"' in z.read(inner + "modelDescription.xml").decode(), c
            assert "aarch64-linux" in folders(z, inner), (c, folders(z, inner))
    with zipfile.ZipFile(FMU_DIR / "containers" / f"{name}.fmu") as z:
        assert folders(z) == {"linux64", "win64", "darwin64"}


def test_fmu_state_of_the_fmi3_container_restores_and_carries_over(tmp_path):
    s = Slave3("PendulumLQR", tmp_path)
    fmu, vr = s.fmu, s.vr
    y = [vr["pendulum.alpha1"], vr["controller.M1"]]
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    for k in range(500):
        fmu.doStep(k * H, H)
    state = fmu.getFMUState()
    serialized = fmu.serializeFMUState(state)

    def on(f):
        rows = []
        for k in range(500, 800):
            f.doStep(k * H, H)
            rows.append(f.getFloat64(y))
        return np.array(rows)

    first = on(fmu)
    fmu.setFMUState(state)
    assert fmu.getFloat64([vr["time"]])[0] == pytest.approx(0.5, abs=1e-12)
    second = on(fmu)
    fmu.freeFMUState(state)
    other = Slave3("PendulumLQR", tmp_path, instance="other")
    st = other.fmu.deserializeFMUState(serialized)
    other.fmu.setFMUState(st)
    third = on(other.fmu)
    other.fmu.freeFMUState(st)
    other.free()
    s.free()
    assert np.array_equal(first, second) and np.array_equal(first, third)


def test_enumerations_are_int64_and_start_values_are_read_before_initialization(tmp_path):
    """Each refusal (fmi3Error) puts the instance in Terminated (FMI 3.0, 2.3.1): fmi3Reset
    brings it back to Instantiated, with the start values again."""
    messages = []
    s = Slave3("PendulumLQR", tmp_path, messages=messages)
    fmu, vr = s.fmu, s.vr
    md = {v.name: v for v in s.md.modelVariables}
    # FMI 3.0 getters in Instantiated: the start values (the SSP's parameter set), or what was set.
    assert fmu.getFloat64([vr["pendulum.alpha1_0"]]) == [0.1]
    fmu.setFloat64([vr["pendulum.alpha1_0"]], [0.2])
    assert fmu.getFloat64([vr["pendulum.alpha1_0"]]) == [0.2]
    assert fmu.getInt64([vr["controller.mode"]]) == [int(md["controller.mode"].start)]
    # A calculated output has none yet.
    with pytest.raises(Exception):
        fmu.getFloat64([vr["controller.M1"]])
    assert any("controller.M1" in m and "no start value" in m for _, _, m in messages), messages
    with pytest.raises(Exception):
        fmu.setFloat64([vr["pendulum.alpha1_0"]], [0.3])
    assert any("Terminated" in m for _, _, m in messages), messages
    fmu.reset()
    assert fmu.getFloat64([vr["pendulum.alpha1_0"]]) == [0.1]
    # An enumeration through Int64, not Int32; an item it does not have refused.
    items = [int(i.value) for i in md["controller.mode"].declaredType.items]
    fmu.setInt64([vr["controller.mode"]], [items[-1]])
    assert fmu.getInt64([vr["controller.mode"]]) == [items[-1]]
    fmu.enterInitializationMode(startTime=0.0)
    assert fmu.getInt64([vr["controller.mode"]]) == [items[-1]]
    fmu.exitInitializationMode()
    fmu.doStep(0.0, H)
    messages.clear()
    with pytest.raises(Exception):
        fmu.getInt32([vr["controller.mode"]])
    assert any("is Enumeration, not Int32" in m for _, _, m in messages), messages
    fmu.reset()
    with pytest.raises(Exception):
        fmu.setInt64([vr["controller.mode"]], [2**40])
    fmu.reset()
    # A type no variable has: the reason, naming the variable.
    messages.clear()
    with pytest.raises(Exception):
        fmu.getFloat32([vr["pendulum.alpha1"]])
    assert any("'pendulum.alpha1'" in m and "not Float32" in m for _, _, m in messages), messages
    fmu.freeInstance()


def test_what_the_fmi3_container_does_not_offer_is_refused_with_the_reason(tmp_path):
    path = container3("PendulumLQR")
    md = fmpy.read_model_description(path)
    unzipped = fmpy.extract(path, unzipdir=tmp_path / "u")
    assert md.modelExchange is None and md.coSimulation.hasEventMode is not True

    for make, kwargs, reason in [
        (FMU3Model, {}, "co-simulation FMU only"),
        (FMU3Slave, {"eventModeUsed": True}, "no event mode"),
    ]:
        messages = []
        fmu = make(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                   instanceName="x")
        with pytest.raises(Exception):
            fmu.instantiate(logMessage=lambda _e, _s, _c, m: messages.append(m.decode()), **kwargs)
        assert any(reason in m for m in messages), messages
    # Event mode, with its reason; then the instance is Terminated (FMI 3.0, 2.3.1) until
    # fmi3Reset, and runs again.
    messages = []
    s = Slave3("PendulumLQR", tmp_path, messages=messages, instance="y")
    s.fmu.enterInitializationMode(startTime=0.0)
    s.fmu.exitInitializationMode()
    with pytest.raises(Exception):
        s.fmu.enterEventMode()
    assert any("hasEventMode = false" in m for _, _, m in messages), messages
    with pytest.raises(Exception):
        s.fmu.doStep(0.0, H)
    s.fmu.reset()
    s.fmu.enterInitializationMode(startTime=0.0)
    s.fmu.exitInitializationMode()
    s.fmu.doStep(0.0, H)
    s.free()


def test_a_container_of_fmi3_components_equals_the_one_of_their_fmi2_twins(tmp_path):
    """target/fmu/fmi3/PendulumLQR.ssp (the FMI 3.0 Pendulum and Controller) as a container, FMI
    2.0 and 3.0: the same variables (the Controller's EnumerationType as the 2.0 SimpleType it is)
    and, in fmpy, the same numbers as the containers of the FMI 2.0 components (0)."""
    out = tmp_path / "PendulumLQR.fmu"
    r = subprocess.run(
        [CARGO_FMU, "fmu", "container", FMU_DIR / "fmi3" / "PendulumLQR.ssp", "-o", out,
         "--target", "x86_64-unknown-linux-gnu"],
        capture_output=True,
        text=True,
        timeout=1800,
    )
    assert r.returncode == 0, r.stderr[-4000:]
    for mine, twin in [(out, FMU_DIR / "containers" / "PendulumLQR.fmu"),
                       (tmp_path / "fmi3" / "PendulumLQR.fmu", container3("PendulumLQR"))]:
        assert validate_fmu(str(mine)) == []
        a, b = fmpy.read_model_description(mine), fmpy.read_model_description(twin)
        assert [(v.name, v.type, v.causality, v.start) for v in a.modelVariables] == [
            (v.name, v.type, v.causality, v.start) for v in b.modelVariables]
        rec = [v.name for v in b.modelVariables if v.causality == "output" and v.type in ("Real", "Float64")]
        ra = fmpy.simulate_fmu(str(mine), stop_time=1.0, step_size=H, output_interval=H, output=rec)
        rb = fmpy.simulate_fmu(str(twin), stop_time=1.0, step_size=H, output_interval=H, output=rec)
        assert max(np.max(np.abs(ra[k] - rb[k])) for k in rec) == 0.0
