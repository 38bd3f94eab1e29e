"""Issue 52, item 1: every `depends` of every crate checked at build time, whichever FMI versions
it exports. An event indicator declared `depends = []` built, validated and passed both checks
while its FMI 3.0 description said `<EventIndicator dependencies=""/>` although z depends on the
temperature; in an FMI-3.0-only crate no `depends` was checked at all (the build's probe ran
through FMI 2.0): a clocked output declared without the input it is computed from, and a
derivative without its state, passed `cargo fmu build`. The build now refuses each, naming the
variable, what it depends on and what to add; the right declarations build without a problem."""

import subprocess

from conftest import outside_crate

THERMOSTAT = '''//! A thermostat with hysteresis: the heater is on below t_low and off above t_high.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A heated room and its thermostat
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Thermostat {
    /// Room temperature
    #[variable(vr = 1, name = "T", output, continuous, initial = exact, start = 15.0, depends = [T])]
    pub temp: f64,
    /// dT/dt
    #[variable(vr = 2, name = "der(T)", local, derivative_of = temp, depends = [T], initial_depends = [T])]
    pub der_temp: f64,
    /// The switching function: T minus the threshold the heater switches at next
    #[variable(vr = 3, name = "z", local, continuous, event_indicator, depends = DEPENDS)]
    pub z: f64,
    /// The heater is on
    pub on: bool,
}

impl Model for Thermostat {
    fn derivatives<D: Real>(&self, _t: D, v: &mut ThermostatContinuous<D>) {
        let heat = if self.on { 2.0 } else { 0.0 };
        v.der_temp = (v.temp - 10.0) * -0.1 + heat;
    }

    fn outputs<D: Real>(&self, _t: D, v: &mut ThermostatContinuous<D>) {
        let threshold = if self.on { 22.0 } else { 18.0 };
        v.z = v.temp - threshold;
    }

    fn update(&mut self, _event: &mut Event) -> Result<(), String> {
        if self.on && self.temp >= 22.0 {
            self.on = false;
        } else if !self.on && self.temp <= 18.0 {
            self.on = true;
        }
        Ok(())
    }
}

impl CoSimulation for Thermostat {}

rustfmu::export_fmu!(Thermostat);
'''

SAMPLED_GAIN = '''//! FMI 3.0 only: a gain sampled by a periodic clock, and a first-order lag of its held output.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A sampled gain and a lag
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only)]
pub struct SampledGain {
    /// Ticks every 0.1 s
    #[variable(vr = 1, input, clock(fixed, interval = 0.1))]
    pub sample: Clock,
    /// Input, read at the ticks
    #[variable(vr = 4, input, discrete, clocks = [sample], start = 0.0)]
    pub u: f64,
    /// 2 u, computed at the tick from the input of the same tick
    #[variable(vr = 5, output, discrete, clocks = [sample], depends = Y_DEPENDS)]
    pub y: f64,
    /// The lag of the held y
    #[variable(vr = 6, output, continuous, initial = exact, start = 0.0, depends = [z])]
    pub z: f64,
    /// dz/dt = y - z
    #[variable(vr = 7, name = "der(z)", local, continuous, derivative_of = z, depends = Z_DEPENDS)]
    pub der_z: f64,
}

impl Model for SampledGain {
    fn derivatives<D: Real>(&self, _t: D, v: &mut SampledGainContinuous<D>) {
        v.der_z = v.z * -1.0 + self.y;
    }

    fn update(&mut self, _event: &mut Event) -> Result<(), String> {
        if self.sample.is_active() {
            self.y = 2.0 * self.u;
        }
        Ok(())
    }
}

impl CoSimulation for SampledGain {}

rustfmu::export_fmi3!(SampledGain);
'''


def build(name, source, fmi3_only=False):
    crate, env = outside_crate(name, fresh=True)
    (crate / "src" / "lib.rs").write_text(source)
    if fmi3_only:
        toml = (crate / "Cargo.toml").read_text()
        toml = toml.replace("[package.metadata.fmu]\n", '[package.metadata.fmu]\nfmi-versions = ["3.0"]\n')
        (crate / "Cargo.toml").write_text(toml)
    return subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=1800)


def test_an_event_indicator_declared_without_its_state_is_refused_by_the_build():
    out = build("thermostat-depends", THERMOSTAT.replace("DEPENDS", "[]"))
    assert out.returncode != 0, out.stderr[-4000:]
    assert ("event indicator 'z' depends on the state 'T'" in out.stderr
            and "`depends = []` leaves out: add 'T'" in out.stderr), out.stderr[-4000:]
    out = build("thermostat-depends", THERMOSTAT.replace("DEPENDS", "[T]"))
    assert out.returncode == 0, out.stderr[-4000:]
    assert "leaves out" not in out.stderr, out.stderr[-4000:]


def test_an_fmi3_only_crate_has_its_depends_checked_through_fmi3_clocked_outputs_too():
    wrong = SAMPLED_GAIN.replace("Y_DEPENDS", "[]").replace("Z_DEPENDS", "[]")
    out = build("sampled-gain-depends", wrong, fmi3_only=True)
    assert out.returncode != 0, out.stderr[-4000:]
    assert ("clocked output 'y' depends at its tick on the input 'u'" in out.stderr
            and "`depends = []` leaves out: add 'u'" in out.stderr), out.stderr[-4000:]
    assert ("derivative 'der(z)' depends on the state 'z'" in out.stderr
            and "by fmi3GetDirectionalDerivative" in out.stderr), out.stderr[-4000:]
    right = SAMPLED_GAIN.replace("Y_DEPENDS", "[u]").replace("Z_DEPENDS", "[z]")
    out = build("sampled-gain-depends", right, fmi3_only=True)
    assert out.returncode == 0, out.stderr[-4000:]
    assert "leaves out" not in out.stderr, out.stderr[-4000:]


def test_an_fmi3_only_crate_builds_without_fmi_versions_and_an_invalid_fmu_is_moved_aside():
    """Issue 52, item 6: `#[fmu(fmi3_only)]` also needed `fmi-versions = ["3.0"]` in Cargo.toml,
    and the hint said to call `export_fmu!` (a compile error for a clocked model); an FMU that
    failed validation stayed in target/fmu/ and `cargo fmu check` then ran on it without a word.
    Now a library that implements FMI 3.0 only is built as FMI 3.0 with a note when nobody asked
    for a version; asked for FMI 2.0, the hint does not suggest export_fmu!; an FMU the build
    finds invalid is moved to `invalid/`, and `cargo fmu check` on its old path says why."""
    from conftest import USER_TARGET
    # Its own model identifier: the crates share one target folder.
    source = SAMPLED_GAIN.replace("SampledGain", "VersionsGain")
    right = source.replace("Y_DEPENDS", "[u]").replace("Z_DEPENDS", "[z]")
    crate, env = outside_crate("sampled-gain-versions", fresh=True)
    (crate / "src" / "lib.rs").write_text(right)
    out = subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=1800)
    assert out.returncode == 0, out.stderr[-4000:]
    assert "implements FMI 3.0 only" in out.stderr and 'fmi-versions = [\\"3.0\\"]' not in out.stderr, out.stderr[-4000:]
    assert (USER_TARGET / "fmu" / "fmi3" / "VersionsGain.fmu").exists()
    out = subprocess.run(["cargo", "fmu", "build", "--fmi-version", "2"], cwd=crate, env=env, capture_output=True,
                         text=True, timeout=1800)
    assert out.returncode != 0
    assert "FMI 3.0 only" in out.stderr and "export_fmu!" not in out.stderr.split("asked for")[-1], out.stderr[-3000:]
    # An invalid FMU (a depends left out) is moved aside.
    wrong = source.replace("Y_DEPENDS", "[]").replace("Z_DEPENDS", "[z]")
    (crate / "src" / "lib.rs").write_text(wrong)
    out = subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=1800)
    assert out.returncode != 0
    fmu = USER_TARGET / "fmu" / "fmi3" / "VersionsGain.fmu"
    assert not fmu.exists(), out.stderr[-3000:]
    assert (fmu.parent / "invalid" / "VersionsGain.fmu").exists(), out.stderr[-3000:]
    out = subprocess.run(["cargo", "fmu", "check", "--strict", str(fmu)], cwd=crate, env=env, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode != 0 and "found this FMU invalid and moved it to" in out.stderr, out.stderr[-3000:]


def test_the_event_checks_run_the_default_experiment_and_see_events_after_two_seconds():
    """Issue 52, item 6: the event checks simulated about 2 s whatever the default experiment
    said, and reported "not declared by the FMU: events" for an FMU that declares an event
    indicator. A thermostat that cools from 25 to the 18 degree threshold at t = 10 ln(15/8) =
    6.3 s, with a default experiment of 20 s: `cargo fmu check` now sees its events in FMI 2.0
    and 3.0 (model exchange, and co-simulation in event mode), and no check says "not declared"
    about events."""
    from conftest import USER_TARGET
    source = (THERMOSTAT.replace("DEPENDS", "[T]").replace("Thermostat", "SlowThermostat")
              .replace("start = 15.0", "start = 25.0"))
    crate, env = outside_crate("slow-thermostat", fresh=True)
    (crate / "src" / "lib.rs").write_text(source)
    toml = (crate / "Cargo.toml").read_text()
    assert "stop-time = 1.0," in toml, toml
    toml = toml.replace("stop-time = 1.0,", "stop-time = 20.0,")
    (crate / "Cargo.toml").write_text(toml)
    out = subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=1800)
    assert out.returncode == 0, out.stderr[-4000:]
    for fmu in (USER_TARGET / "fmu" / "SlowThermostat.fmu", USER_TARGET / "fmu" / "fmi3" / "SlowThermostat.fmu"):
        out = subprocess.run(["cargo", "fmu", "check", "--strict", str(fmu), "--filter", "events", "--random-sequences", "1"],
                             cwd=crate, env=env, capture_output=True, text=True, timeout=900)
        assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
        assert "not declared by the FMU: events" not in out.stdout, out.stdout[-4000:]
        assert "never changed domain" not in out.stdout, out.stdout[-4000:]
        events = [int(n) for n in __import__("re").findall(r"(\d+) events(?:,| handed)", out.stdout)]
        assert events and max(events) >= 1, out.stdout[-4000:]


def test_a_crate_says_which_start_values_its_documentation_page_runs_from():
    """Issue 52, item 6: the documentation page plots the default experiment from the start
    values; the Pendulum's are the upright equilibrium, so its page showed ten flat lines. A crate
    now names start values for the page's run (`documentation-start` in [package.metadata.fmu]):
    the thermostat from 25 degrees plots a falling T (the title says where it starts); a name
    the model does not have stops the build with a message naming it."""
    import re
    import zipfile
    from conftest import USER_TARGET
    source = THERMOSTAT.replace("DEPENDS", "[T]").replace("Thermostat", "PageThermostat")
    crate, env = outside_crate("page-thermostat", fresh=True)
    (crate / "src" / "lib.rs").write_text(source)
    toml = (crate / "Cargo.toml").read_text()
    (crate / "Cargo.toml").write_text(toml.replace("[package.metadata.fmu]\n",
                                                   "[package.metadata.fmu]\ndocumentation-start = { T = 25.0 }\n"))
    out = subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=1800)
    assert out.returncode == 0, out.stderr[-4000:]
    with zipfile.ZipFile(USER_TARGET / "fmu" / "PageThermostat.fmu") as z:
        page = z.read("documentation/index.html").decode()
    assert "from T = 25" in page, page[:3000]
    (crate / "Cargo.toml").write_text(toml.replace("[package.metadata.fmu]\n",
                                                   "[package.metadata.fmu]\ndocumentation-start = { Tx = 25.0 }\n"))
    out = subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=1800)
    assert out.returncode != 0 and "documentation-start: the model has no variable 'Tx'" in out.stderr, out.stderr[-3000:]


INPUT_THERMOSTAT = '''//! A thermostat whose room temperature is an input, and a counter of its switches as Int64.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A heated room, its thermostat and a switch counter
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only)]
pub struct InputThermostat {
    /// Room temperature (outside the heated body)
    #[variable(vr = 0, name = "T_room", input, continuous, start = 10.0)]
    pub t_room: f64,
    /// Body temperature
    #[variable(vr = 1, name = "T", output, continuous, initial = exact, start = 15.0, depends = [T])]
    pub temp: f64,
    /// dT/dt
    #[variable(vr = 2, name = "der(T)", local, derivative_of = temp, depends = [T, T_room], initial_depends = [T, T_room])]
    pub der_temp: f64,
    /// T minus the threshold the heater switches at next
    #[variable(vr = 3, name = "z", local, continuous, event_indicator, depends = [T])]
    pub z: f64,
    /// Minus one, then minus the number of switches (an Int64 whose bits are a NaN's)
    #[variable(vr = 4, output, discrete, initial = exact, start = -5, depends = [])]
    pub count: i64,
    /// The heater is on
    pub on: bool,
}

impl Model for InputThermostat {
    fn derivatives<D: Real>(&self, _t: D, v: &mut InputThermostatContinuous<D>) {
        let heat = if self.on { 2.0 } else { 0.0 };
        v.der_temp = (v.temp - v.t_room) * -0.1 + heat;
    }

    fn outputs<D: Real>(&self, _t: D, v: &mut InputThermostatContinuous<D>) {
        let threshold = if self.on { 22.0 } else { 18.0 };
        v.z = v.temp - threshold;
    }

    fn update(&mut self, _event: &mut Event) -> Result<(), String> {
        if self.on && self.temp >= 22.0 {
            self.on = false;
            self.count -= 1;
        } else if !self.on && self.temp <= 18.0 {
            self.on = true;
            self.count -= 1;
        }
        Ok(())
    }
}

impl CoSimulation for InputThermostat {}

rustfmu::export_fmi3!(InputThermostat);
'''


def test_the_checks_see_events_that_depend_on_an_input_and_read_an_int64_as_an_int64():
    """Found by the new user's trial of issue 52: (1) the event checks moved every input off its
    start value before the run and then reported "none in 40 s ... from the start values" for a
    thermostat whose room temperature is an input (from the start values it switches 8 times);
    (2) the model-exchange Euler check read the variables of other types as f64 bits and failed
    an FMU whose Int64 output is -5 ("non-finite values ... NaN"). The event checks now run from
    the start values first (and with the inputs moved only where no event happened there); the
    finiteness check reads the Float64 values only."""
    from conftest import USER_TARGET
    crate, env = outside_crate("input-thermostat", fresh=True)
    (crate / "src" / "lib.rs").write_text(INPUT_THERMOSTAT)
    toml = (crate / "Cargo.toml").read_text()
    (crate / "Cargo.toml").write_text(toml.replace("stop-time = 1.0,", "stop-time = 40.0,"))
    out = subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=1800)
    assert out.returncode == 0, out.stderr[-4000:]
    fmu = USER_TARGET / "fmu" / "fmi3" / "InputThermostat.fmu"
    out = subprocess.run(["cargo", "fmu", "check", "--strict", str(fmu), "--random-sequences", "20"], cwd=crate, env=env,
                         capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stdout[-5000:] + out.stderr[-2000:]
    assert "never changed domain" not in out.stdout, out.stdout[-5000:]
    assert "from the start values: " in out.stdout and "events handed to the importer" in out.stdout, out.stdout[-5000:]
    me = __import__("re").search(r"up to t = \S+ from the start values: (\d+) events", out.stdout)
    assert me and int(me.group(1)) >= 2, out.stdout[-5000:]
