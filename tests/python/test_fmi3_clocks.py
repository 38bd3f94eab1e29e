"""Issue 25: FMI 3.0 clocks end to end. A user's crate (made by `cargo fmu new`, outside this
workspace) declares a sampled controller: a periodic input clock whose interval is the fixed
parameter Ts, clocked inputs and outputs, and a continuous state between the ticks. `cargo fmu
build` packages it (its smoke run with eventModeUsed), fmpy's validator and fmutool accept the
description, and an importer written here with fmpy's low-level classes runs it in Model Exchange
and in Co-Simulation with event mode, activating the clock at its ticks: the clocked output changes
at the ticks only, equal to the difference equation computed here, and both interfaces agree."""

import math
import pathlib
import re
import shutil
import subprocess
import sys

import fmpy
import fmpy.validation
from fmpy.fmi3 import FMU3Model, FMU3Slave
import pytest

from conftest import USER_TARGET, outside_crate

FMU = USER_TARGET / "fmu" / "fmi3" / "SampledLag.fmu"

MODEL = '''//! A sampled first-order filter y[k+1] = y[k] + Ts/T (u[k] - y[k]) at the ticks of a periodic
//! clock of interval Ts, and the integral z of its held output between the ticks.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A sampled lag and the integral of its output
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only)]
pub struct SampledLag {
    /// Ticks every Ts
    #[variable(vr = 1, input, clock(fixed, interval = Ts))]
    pub sample: Clock,
    /// Sample period
    #[variable(vr = 2, name = "Ts", parameter, fixed, start = 0.1, unit = "s", min > 0.0)]
    pub ts: f64,
    /// Time constant
    #[variable(vr = 3, name = "T", parameter, fixed, start = 0.5, unit = "s", min > 0.0)]
    pub t: f64,
    /// Input, read at the ticks
    #[variable(vr = 4, input, discrete, clocks = [sample], start = 0.0)]
    pub u: f64,
    /// Filtered input, changed at the ticks (one sample of delay)
    #[variable(vr = 5, output, discrete, clocks = [sample], depends = [])]
    pub y: f64,
    /// The integral of the held y
    #[variable(vr = 6, output, continuous, initial = exact, start = 0.0, depends = [z])]
    pub z: f64,
    /// dz/dt = y
    #[variable(vr = 7, name = "der(z)", local, continuous, derivative_of = z, depends = [])]
    pub der_z: f64,
    /// Ticks where y rises through 0.5 (at a tick of `sample`)
    #[variable(vr = 8, output, clock(triggered), depends = [])]
    pub high: Clock,
    /// How often y rose through 0.5
    #[variable(vr = 9, output, discrete, clocks = [high])]
    pub highs: i32,
    /// The filter's state: the output of the next tick
    pub next: f64,
}

impl Model for SampledLag {
    fn derivatives<D: Real>(&self, _t: D, v: &mut SampledLagContinuous<D>) {
        v.der_z = v.z * 0.0 + self.y;
    }

    fn update(&mut self, _event: &mut Event) -> Result<(), String> {
        if self.sample.is_active() {
            let before = self.y;
            self.y = self.next;
            self.next = self.y + self.ts / self.t * (self.u - self.y);
            if before < 0.5 && self.y >= 0.5 {
                self.high.tick();
                self.highs += 1;
            }
        }
        Ok(())
    }
}

impl CoSimulation for SampledLag {}

rustfmu::export_fmi3!(SampledLag);
'''

TS, T, STOP = 0.1, 0.5, 2.0


def u_of(t):
    return math.sin(3.0 * t)


def expected():
    """y at each tick k (t = k Ts), and z(STOP) = the sum of y[k] Ts; the ticks where y rises
    through 0.5 (the output clock `high`)."""
    y, nxt, ys, highs = 0.0, 0.0, [], []
    for k in range(int(round(STOP / TS)) + 1):
        before, y = y, nxt
        nxt = y + TS / T * (u_of(k * TS) - y)
        ys.append(y)
        if before < 0.5 <= y:
            highs.append(k)
    return ys, sum(ys[:-1]) * TS, highs


@pytest.fixture(scope="module")
def sampled_lag():
    crate, env = outside_crate("sampled-lag", fresh=True)
    (crate / "src" / "lib.rs").write_text(MODEL)
    toml = (crate / "Cargo.toml").read_text()
    toml = toml.replace("[package.metadata.fmu]\n", '[package.metadata.fmu]\nfmi-versions = ["3.0"]\n')
    (crate / "Cargo.toml").write_text(toml)
    out = subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=1800)
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-4000:]
    assert FMU.exists()
    return str(FMU)


def test_the_description_is_valid_and_declares_the_clock(sampled_lag):
    assert fmpy.validation.validate_fmu(sampled_lag) == []
    md = fmpy.read_model_description(sampled_lag)
    v = {x.name: x for x in md.modelVariables}
    assert v["sample"].type == "Clock" and v["sample"].causality == "input"
    assert v["sample"].intervalVariability == "fixed"
    assert [c.name for c in v["y"].clocks] == ["sample"] and [c.name for c in v["u"].clocks] == ["sample"]
    assert v["high"].type == "Clock" and v["high"].causality == "output" and v["high"].intervalVariability == "triggered"
    assert [c.name for c in v["highs"].clocks] == ["high"]
    assert "high" in [o.variable.name for o in md.outputs]
    # A clocked output depends on its clock, and is no initial unknown.
    out = {o.variable.name: o for o in md.outputs}
    assert "sample" in [d.name for d in out["y"].dependencies]
    assert "y" not in [u.variable.name for u in md.initialUnknowns]
    fmutool = shutil.which("fmutool") or shutil.which("fmutool", path=str(pathlib.Path(sys.executable).parent))
    if fmutool:
        r = subprocess.run([fmutool, "-input", sampled_lag, "-check"], capture_output=True, text=True, timeout=300)
        # Its log lines start with the level ("ERROR    | ..."); "No semantic error" is fine.
        errors = [line for line in (r.stdout + r.stderr).splitlines() if re.match(r"^\s*(ERROR|CRITICAL)\b", line)]
        assert r.returncode == 0 and not errors and "No semantic error" in r.stdout, r.stdout + r.stderr


def vr_of(path):
    md = fmpy.read_model_description(path)
    return md, {x.name: x.valueReference for x in md.modelVariables}


def tick(fmu, vr, t, seen, highs=None):
    """Event Mode at a tick: activate the clock, set the clocked input, read the clocked output
    (evaluating the tick), ask whether the output clock `high` ticks (and then read what it
    clocks), update."""
    fmu.setClock([vr["sample"]], [True])
    fmu.setFloat64([vr["u"]], [u_of(t)])
    seen.append(fmu.getFloat64([vr["y"]])[0])
    if highs is not None and fmu.getClock([vr["high"]])[0]:
        highs.append((len(seen) - 1, fmu.getInt32([vr["highs"]])[0]))
    again = True
    while again:
        again, terminate, *_ = fmu.updateDiscreteStates()
        assert not terminate


def test_model_exchange_activates_the_clock_at_its_ticks(sampled_lag):
    md, vr = vr_of(sampled_lag)
    unzipped = fmpy.extract(sampled_lag)
    fmu = FMU3Model(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.modelExchange.modelIdentifier,
                    instanceName="me")
    fmu.instantiate()
    fmu.enterInitializationMode(startTime=0.0)
    # The interval is the parameter Ts: "changed" (2) when first read, in Initialization Mode.
    import ctypes
    h, q = (ctypes.c_double * 1)(), (ctypes.c_int * 1)()
    fmu.getIntervalDecimal((ctypes.c_uint * 1)(vr["sample"]), h, q)
    assert (h[0], q[0]) == (TS, 2)
    fmu.exitInitializationMode()
    seen, highs, t, k = [], [], 0.0, 0
    n = int(round(STOP / TS))
    x = (ctypes.c_double * 1)()
    dx = (ctypes.c_double * 1)()
    while True:
        tick(fmu, vr, t, seen, highs)
        if k == n:
            break
        fmu.enterContinuousTimeMode()
        # Between the ticks: explicit Euler on dz/dt = y (y held: exact for any step).
        for _ in range(4):
            fmu.getContinuousStates(x, 1)
            fmu.getContinuousStateDerivatives(dx, 1)
            t += TS / 4
            fmu.setTime(t)
            x[0] += TS / 4 * dx[0]
            fmu.setContinuousStates(x, 1)
            enter, terminate = fmu.completedIntegratorStep()
            assert not enter and not terminate
        k += 1
        t = k * TS
        fmu.setTime(t)
        fmu.enterEventMode()
    ys, z, want_highs = expected()
    assert max(abs(a - b) for a, b in zip(seen, ys)) < 1e-12, (seen, ys)
    assert abs(fmu.getFloat64([vr["z"]])[0] - z) < 1e-12
    # The output clock ticked where y rose through 0.5, and counted each.
    assert want_highs and highs == [(k, i + 1) for i, k in enumerate(want_highs)], (highs, want_highs)
    fmu.terminate()
    fmu.freeInstance()


def test_co_simulation_with_event_mode_agrees(sampled_lag):
    md, vr = vr_of(sampled_lag)
    unzipped = fmpy.extract(sampled_lag)
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="cs")
    fmu.instantiate(eventModeUsed=True)
    fmu.enterInitializationMode(startTime=0.0, stopTime=STOP)
    fmu.exitInitializationMode()
    seen = []
    n = int(round(STOP / TS))
    for k in range(n + 1):
        tick(fmu, vr, k * TS, seen)
        if k == n:
            break
        fmu.enterStepMode()
        event, terminate, early, last = fmu.doStep(k * TS, TS)
        assert not terminate and not early
        fmu.enterEventMode()
    ys, z, _ = expected()
    assert max(abs(a - b) for a, b in zip(seen, ys)) < 1e-12
    # The runtime's integrator between the ticks: z = sum of y Ts to its tolerance.
    assert abs(fmu.getFloat64([vr["z"]])[0] - z) < 1e-6
    fmu.terminate()
    fmu.freeInstance()


def test_co_simulation_without_event_mode_is_refused_with_the_reason(sampled_lag):
    md, _ = vr_of(sampled_lag)
    messages = []
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=fmpy.extract(sampled_lag),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="cs")
    with pytest.raises(Exception):
        fmu.instantiate(eventModeUsed=False, logMessage=lambda *a: messages.append(a[-1]))
    assert any(b"eventModeUsed = true" in m for m in messages), messages


def test_cargo_fmu_check_passes_on_the_clocked_fmu(sampled_lag):
    """The conformance suite on an FMU with input and output clocks: its clock check (an importer
    that activates the input clocks at their ticks and asks for the output clocks at every event)
    and every other check, which run its co-simulation with eventModeUsed as the standard requires."""
    crate, env = outside_crate("sampled-lag")
    out = subprocess.run(["cargo", "fmu", "check", "--strict", sampled_lag], cwd=crate, env=env, capture_output=True, text=True,
                         timeout=900)
    summary = [line for line in out.stdout.splitlines() if " passed, " in line and " failed" in line]
    assert out.returncode == 0 and summary and " 0 failed" in summary[-1], out.stdout[-6000:] + out.stderr[-2000:]
    assert "PASS  model exchange / fmi3_clocks_tick_where_their_intervals_say" in out.stdout, out.stdout[-3000:]
