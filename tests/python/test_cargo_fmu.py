"""A Rust developer's path from nothing to a validated FMU of their own crate, outside this
workspace, with the `cargo fmu` this workspace builds (target/release/cargo-fmu on PATH is what
`cargo install --path fmu-build` gives): `cargo fmu new`, a change to the model, `cargo fmu
build`, fmpy's validator, `fmpy.simulate_fmu` against the analytic answer, `cargo fmu check`."""

import hashlib
import math
import re
import subprocess
import zipfile
from pathlib import Path

import fmpy
import fmpy.validation
import pytest

from conftest import USER_TARGET, outside_crate

FMUS = USER_TARGET / "fmu"


def run(args, cwd, env):
    out = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, f"{' '.join(map(str, args))} failed ({out.returncode}):\n{out.stdout}\n{out.stderr}"
    return out


GAIN_FIELD = '''    /// Gain K of the lag: T dy/dt = K u - y
    #[variable(vr = 4, name = "K", parameter, tunable, start = 1.0, min > 0.0)]
    pub gain: f64,
'''


@pytest.fixture(scope="module")
def user_crate():
    """A crate made anew by `cargo fmu new gain-lag` outside the workspace and changed as a user
    would; built into the tests' shared target folder of such crates (CARGO_TARGET_DIR)."""
    crate, env = outside_crate("gain-lag", fresh=True)
    lib = crate / "src" / "lib.rs"
    src = lib.read_text()
    # The user's change: a gain K (tunable, > 0), so that y follows K u.
    assert "pub time_constant: f64,\n}" in src, src
    src = src.replace("pub time_constant: f64,\n}", "pub time_constant: f64,\n" + GAIN_FIELD + "}")
    src = src.replace("self.y = self.u + (self.y - self.u)", "self.y = self.gain * self.u + (self.y - self.gain * self.u)")
    # ... in the equations too (model exchange, directional derivatives).
    assert "v.der_y = (v.u - v.y) / self.time_constant;" in src, src
    src = src.replace("v.der_y = (v.u - v.y) / self.time_constant;", "v.der_y = (v.u * self.gain - v.y) / self.time_constant;")
    # ... and in der(y)'s dependencies at initialization, which `cargo fmu build` checks (it
    # refuses the template's `initial_depends = [u, y, T]` now: "add 'K' to it").
    assert "initial_depends = [u, y, T])]" in src, src
    src = src.replace("initial_depends = [u, y, T])]", "initial_depends = [u, y, T, K])]")
    lib.write_text(src)
    build = run(["cargo", "fmu", "build"], crate, env)
    fmu = FMUS / "GainLag.fmu"
    assert fmu.exists(), build.stderr
    assert (FMUS / "fmi3" / "GainLag.fmu").exists(), build.stderr
    return crate, fmu, env


@pytest.fixture(scope="module")
def user_fmu3(user_crate):
    crate, _, env = user_crate
    return crate, FMUS / "fmi3" / "GainLag.fmu", env


def test_the_new_crate_packages_a_valid_fmu(user_crate):
    _, fmu, _ = user_crate
    assert fmpy.validation.validate_fmu(str(fmu)) == []
    md = fmpy.read_model_description(str(fmu))
    assert md.coSimulation.modelIdentifier == "GainLag"
    assert md.modelExchange.modelIdentifier == "GainLag"
    assert md.coSimulation.providesDirectionalDerivative and md.modelExchange.providesDirectionalDerivative
    names = {v.name: v for v in md.modelVariables}
    assert set(names) == {"u", "y", "der(y)", "T", "K"}
    assert [d.variable.name for d in md.derivatives] == ["der(y)"]
    assert names["K"].causality == "parameter" and names["K"].variability == "tunable"
    assert names["T"].unit == "s" and float(names["T"].min) > 0


def test_the_fmus_page_shows_the_default_experiment(user_crate):
    """Issue 23: an engineer opening an FMU in a tool looks before reading. The FMU's
    documentation/index.html shows its default experiment as an SVG chart of its Real outputs,
    simulated by `cargo fmu build` through co-simulation; in both versions' packages."""
    import xml.etree.ElementTree as ET
    _, fmu, _ = user_crate
    for path in (fmu, FMUS / "fmi3" / "GainLag.fmu"):
        with zipfile.ZipFile(path) as z:
            html = z.read("documentation/index.html").decode()
        assert "<h2>Default experiment</h2>" in html, html[:2000]
        svg = html[html.index("<svg"):html.index("</svg>") + len("</svg>")]
        chart = ET.fromstring(svg)
        ns = "{http://www.w3.org/2000/svg}"
        lines = chart.findall(f"{ns}polyline")
        assert len(lines) == 1, svg
        # The lag's output y from its start value: one point per recorded time, all finite.
        points = [tuple(map(float, p.split(","))) for p in lines[0].get("points").split()]
        assert len(points) > 10, svg
        assert [t.text for t in chart.findall(f"{ns}text") if t.text == "y"], svg


def test_the_fmu_simulates_the_analytic_step_response(user_crate):
    _, fmu, _ = user_crate
    K, T = 3.0, 0.2
    r = fmpy.simulate_fmu(str(fmu), start_values={"u": 1.0, "K": K, "T": T}, stop_time=1.0, output_interval=0.01)
    worst = max(abs(y - K * (1.0 - math.exp(-t / T))) for t, y in zip(r["time"], r["y"]))
    assert len(r) == 101 and worst < 1e-12, f"largest deviation from K (1 - exp(-t/T)): {worst}"


def test_the_fmu_simulates_the_analytic_step_response_in_model_exchange(user_crate):
    _, fmu, _ = user_crate
    K, T = 3.0, 0.2
    r = fmpy.simulate_fmu(
        str(fmu), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10,
        start_values={"u": 1.0, "K": K, "T": T}, stop_time=1.0, output_interval=0.01,
    )
    worst = max(abs(y - K * (1.0 - math.exp(-t / T))) for t, y in zip(r["time"], r["y"]))
    # CVode at rtol 1e-10 on a lag of amplitude 3: measured 2e-9 here.
    assert worst < 1e-7, f"largest deviation from K (1 - exp(-t/T)) under CVode: {worst}"


def test_the_crates_own_test_passes(user_crate):
    crate, _, env = user_crate
    out = run(["cargo", "test", "--release"], crate, env)
    assert "1 passed" in out.stdout, out.stdout


def test_cargo_fmu_info_and_validate_describe_it(user_crate):
    crate, fmu, env = user_crate
    info = run(["cargo", "fmu", "info", str(fmu)], crate, env).stdout
    assert "GainLag" in info and "linux64" in info and "CoSimulation" in info and "ModelExchange" in info, info
    # The oldest glibc the Linux binary loads with, read from its symbol versions (issue 27).
    assert re.search(r"binaries/linux64/GainLag\.so needs glibc >= 2\.\d+", info), info
    out = run(["cargo", "fmu", "validate", str(fmu)], crate, env)
    assert re.search(r"GainLag\.so needs glibc >= 2\.\d+", out.stderr), out.stderr


def test_cargo_fmu_check_passes_on_it(user_crate):
    crate, fmu, env = user_crate
    out = run(["cargo", "fmu", "check", "--strict", str(fmu)], crate, env)
    assert " 0 failed" in out.stdout, out.stdout


# ---- FMI 3.0: the same crate's binary (it serves both versions), packaged by the same `cargo fmu build`

def test_the_new_crate_packages_a_valid_fmi3_fmu(user_fmu3):
    _, fmu, _ = user_fmu3
    assert fmpy.validation.validate_fmu(str(fmu)) == []
    md = fmpy.read_model_description(str(fmu))
    assert md.fmiVersion == "3.0"
    assert md.coSimulation.modelIdentifier == "GainLag" and md.modelExchange.modelIdentifier == "GainLag"
    names = {v.name: v for v in md.modelVariables}
    assert set(names) == {"time", "u", "y", "der(y)", "T", "K"}
    assert names["time"].causality == "independent"
    assert [d.variable.name for d in md.derivatives] == ["der(y)"]
    assert names["der(y)"].derivative is names["y"]
    import zipfile
    with zipfile.ZipFile(fmu) as z:
        files = set(z.namelist())
        xml = z.read("modelDescription.xml").decode()
    assert "binaries/x86_64-linux/GainLag.so" in files and not any(f.startswith("binaries/linux64/") for f in files), files
    assert 'fmiVersion="3.0"' in xml and "instantiationToken=" in xml


def test_the_fmi3_fmu_simulates_the_analytic_step_response(user_fmu3):
    _, fmu, _ = user_fmu3
    K, T = 3.0, 0.2
    for fmi_type in ["CoSimulation", "ModelExchange"]:
        r = fmpy.simulate_fmu(str(fmu), fmi_type=fmi_type, start_values={"u": 1.0, "K": K, "T": T},
                              stop_time=1.0, output_interval=0.01, relative_tolerance=1e-10)
        worst = max(abs(y - K * (1.0 - math.exp(-t / T))) for t, y in zip(r["time"], r["y"]))
        assert worst < (1e-12 if fmi_type == "CoSimulation" else 1e-6), f"{fmi_type}: largest deviation {worst}"


def test_cargo_fmu_info_and_validate_describe_the_fmi3_fmu(user_fmu3):
    crate, fmu, env = user_fmu3
    info = run(["cargo", "fmu", "info", str(fmu)], crate, env).stdout
    assert "FMI 3.0" in info and "x86_64-linux" in info and "GainLag" in info, info
    run(["cargo", "fmu", "validate", str(fmu)], crate, env)


def test_cargo_fmu_build_makes_the_versions_asked_for(user_crate):
    crate, _, env = user_crate
    fmu2, fmu3 = FMUS / "GainLag.fmu", FMUS / "fmi3" / "GainLag.fmu"
    try:
        fmu2.unlink()
        fmu3.unlink()
        run(["cargo", "fmu", "build", "--fmi-version", "3"], crate, env)
        assert fmu3.exists() and not fmu2.exists()
        bad = subprocess.run(["cargo", "fmu", "build", "--fmi-version", "4"], cwd=crate, env=env,
                             capture_output=True, text=True, timeout=900)
        assert bad.returncode != 0 and "--fmi-version" in bad.stderr, bad.stderr
    finally:
        run(["cargo", "fmu", "build"], crate, env)
    assert fmu2.exists() and fmu3.exists()


def test_a_crate_that_calls_export_fmi2_is_told_to_call_export_fmu(user_crate):
    """A crate that calls `export_fmi2!` gets what its library implements, FMI 2.0, with a note
    naming `export_fmu!` (both versions) and `fmi-versions` (issue 52: the tool can see which
    versions a library implements; a default build no longer fails on it). Asked for FMI 3.0 by
    name, the build fails and says how to get it."""
    crate, _, env = user_crate
    lib = crate / "src" / "lib.rs"
    src = lib.read_text()
    assert "rustfmu::export_fmu!(GainLag);" in src, src
    fmu3 = FMUS / "fmi3" / "GainLag.fmu"
    try:
        lib.write_text(src.replace("rustfmu::export_fmu!(GainLag);", "rustfmu::export_fmi2!(GainLag);"))
        fmu3.unlink(missing_ok=True)
        out = run(["cargo", "fmu", "build"], crate, env)
        assert ("implements FMI 2.0 only (it calls rustfmu::export_fmi2!): FMI 3.0 is not built" in out.stderr
                and "export_fmu!(YourModel)` exports both versions" in out.stderr), out.stderr[-3000:]
        assert (FMUS / "GainLag.fmu").exists() and not fmu3.exists()
        bad = subprocess.run(["cargo", "fmu", "build", "--fmi-version", "3"], cwd=crate, env=env, capture_output=True,
                             text=True, timeout=900)
        assert bad.returncode != 0 and "export_fmu!" in bad.stderr and "export_fmi2!" in bad.stderr, bad.stderr
        # Only FMI 2.0 asked for: it builds.
        run(["cargo", "fmu", "build", "--fmi-version", "2"], crate, env)
    finally:
        lib.write_text(src)
        run(["cargo", "fmu", "build"], crate, env)


def test_the_crates_metadata_chooses_its_fmi_versions(user_crate):
    crate, _, env = user_crate
    manifest = crate / "Cargo.toml"
    text = manifest.read_text()
    assert "[package.metadata.fmu]" in text, text
    fmu2, fmu3 = FMUS / "GainLag.fmu", FMUS / "fmi3" / "GainLag.fmu"
    try:
        manifest.write_text(text.replace("[package.metadata.fmu]", '[package.metadata.fmu]\nfmi-versions = ["3.0"]', 1))
        fmu2.unlink()
        fmu3.unlink()
        run(["cargo", "fmu", "build"], crate, env)
        assert fmu3.exists() and not fmu2.exists()
        manifest.write_text(text.replace("[package.metadata.fmu]", '[package.metadata.fmu]\nfmi-versions = ["4.0"]', 1))
        bad = subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=900)
        assert bad.returncode != 0 and "fmi-versions" in bad.stderr, bad.stderr
    finally:
        manifest.write_text(text)
        run(["cargo", "fmu", "build"], crate, env)
    assert fmu2.exists() and fmu3.exists()


def test_each_target_is_built_once_for_both_fmi_versions(user_crate):
    """One cargo build per target, whose binary goes into the FMI 2.0 and the FMI 3.0 FMU."""
    crate, _, env = user_crate
    # -v: the cargo commands and cargo's messages as they come.
    out = run(["cargo", "fmu", "build", "-v"], crate, env)
    builds = re.findall(r"^fmu: \S*cargo rustc (.*)$", out.stderr, re.M)
    # One `cargo rustc` of the library alone (--crate-type cdylib: link-time optimisation, which an
    # rlib beside it would switch off), in the FMU profile.
    assert len(builds) == 1, out.stderr
    assert builds[0].startswith("--profile fmu-release ") and builds[0].endswith("--lib --crate-type cdylib -p gain-lag"), builds
    binaries = []
    for fmu, folder in [(FMUS / "GainLag.fmu", "linux64"), (FMUS / "fmi3" / "GainLag.fmu", "x86_64-linux")]:
        with zipfile.ZipFile(fmu) as z:
            binaries.append(z.read(f"binaries/{folder}/GainLag.so"))
    assert binaries[0] == binaries[1]


def test_the_build_shows_its_progress_and_cargos_messages_only_on_failure(user_crate):
    """Without -v, in a log (no terminal): one line per crate built with the count and the time, a
    summary, none of cargo's own lines; a build that fails shows all of cargo's messages of it."""
    crate, _, env = user_crate
    lib = crate / "src" / "lib.rs"
    lib.write_text(lib.read_text() + "\n// touched\n")
    out = run(["cargo", "fmu", "build"], crate, env)
    assert re.search(r"^fmu: \[1/1\] built gain-lag for \S+ in [0-9.]+ s", out.stderr, re.M), out.stderr
    assert re.search(r"^fmu: built 1 libraries for 1 targets in ", out.stderr, re.M), out.stderr
    assert "Compiling" not in out.stderr and "Finished" not in out.stderr, out.stderr
    text = lib.read_text()
    try:
        lib.write_text(text + "\nfn broken() -> u32 { \"not a number\" }\n")
        bad = subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=900)
        assert bad.returncode != 0, bad.stderr
        assert "mismatched types" in bad.stderr and "Compiling gain-lag" in bad.stderr, bad.stderr
        assert "cargo rustc of gain-lag failed" in bad.stderr, bad.stderr
    finally:
        lib.write_text(text)


def test_a_crate_sharing_the_target_folder_cannot_replace_another_crates_fmu(user_crate):
    """Two crates built into one CARGO_TARGET_DIR whose models have the same identifier: the second
    is refused with both crates named, and the first one's FMUs stay as they were."""
    crate, fmu, env = user_crate
    other, _ = outside_crate("other-lag", fresh=True)
    lib = other / "src" / "lib.rs"
    lib.write_text(lib.read_text().replace("OtherLag", "GainLag"))
    fmu3 = FMUS / "fmi3" / "GainLag.fmu"
    before = [hashlib.sha256(f.read_bytes()).hexdigest() for f in (fmu, fmu3)]
    bad = subprocess.run(["cargo", "fmu", "build"], cwd=other, env=env, capture_output=True, text=True, timeout=900)
    assert bad.returncode != 0, bad.stderr
    assert "'gain-lag'" in bad.stderr and "other-lag" in bad.stderr and "same identifier 'GainLag'" in bad.stderr, bad.stderr
    assert "nothing was written" in bad.stderr, bad.stderr
    assert [hashlib.sha256(f.read_bytes()).hexdigest() for f in (fmu, fmu3)] == before
    # Its own name: it builds beside the other.
    lib.write_text(lib.read_text().replace("GainLag", "OtherLag"))
    run(["cargo", "fmu", "build"], other, env)
    assert (FMUS / "OtherLag.fmu").exists() and [hashlib.sha256(f.read_bytes()).hexdigest() for f in (fmu, fmu3)] == before


TABLE_FIELD = '''    /// Gain K of the lag, read from resources/gain.txt at initialization: T dy/dt = K u - y
    #[variable(vr = 4, name = "K", calculated_parameter)]
    pub gain: f64,
'''

TABLE_INIT = '''
    /// K from the FMU's own resources/gain.txt, as the importer unpacked it.
    fn initialize(&mut self, ctx: &Context) -> Result<(), String> {
        let dir = ctx.resource_dir().ok_or("no resource folder: K is read from resources/gain.txt")?;
        let text = std::fs::read_to_string(dir.join("gain.txt")).map_err(|e| format!("resources/gain.txt: {e}"))?;
        self.gain = text.trim().parse().map_err(|e| format!("resources/gain.txt: {e}"))?;
        Ok(())
    }
'''


def test_a_model_that_reads_its_resources_builds_checks_and_simulates():
    """Issue 23: a model that reads its packaged resources/ at initialization. `cargo fmu build`'s
    smoke run and `cargo fmu check` give it the FMU's own unpacked resources/ folder, as an
    importer does; fmpy then simulates the gain read from it."""
    crate, env = outside_crate("table-lag", fresh=True)
    lib = crate / "src" / "lib.rs"
    src = lib.read_text()
    src = src.replace("pub time_constant: f64,\n}", "pub time_constant: f64,\n" + TABLE_FIELD + "}")
    src = src.replace("v.der_y = (v.u - v.y) / self.time_constant;\n    }",
                      "v.der_y = (v.u * self.gain - v.y) / self.time_constant;\n    }" + TABLE_INIT)
    src = src.replace("self.y = self.u + (self.y - self.u)", "self.y = self.gain * self.u + (self.y - self.gain * self.u)")
    assert src.count("self.gain") == 4, src
    # The template's unit test runs the model without resources: it reads no table.
    src = src.split("#[cfg(test)]")[0]
    lib.write_text(src)
    (crate / "resources").mkdir(exist_ok=True)
    (crate / "resources" / "gain.txt").write_text("2.5\n")
    run(["cargo", "fmu", "build"], crate, env)
    for fmu in (FMUS / "TableLag.fmu", FMUS / "fmi3" / "TableLag.fmu"):
        with zipfile.ZipFile(fmu) as z:
            assert z.read("resources/gain.txt") == b"2.5\n"
        out = subprocess.run(["cargo", "fmu", "check", "--strict", str(fmu)], cwd=crate, env=env, capture_output=True, text=True,
                             timeout=900)
        summary = [l for l in out.stdout.splitlines() if re.match(r"^\d+ passed, \d+ failed", l)]
        assert out.returncode == 0 and summary and " 0 failed" in summary[-1], out.stdout[-6000:] + out.stderr[-2000:]
        result = fmpy.simulate_fmu(str(fmu), stop_time=1.0, output_interval=0.01, start_values={"u": 1.0},
                                   output=["y", "K"])
        assert result["K"][-1] == 2.5
        assert abs(result["y"][-1] - 2.5 * (1.0 - math.exp(-1.0 / 0.1))) < 1e-6, result["y"][-1]


def check_clean(crate, env, model_identifier):
    """`cargo fmu check` of the crate's FMI 2.0 and 3.0 FMUs: 0 failed in each."""
    for fmu in (FMUS / f"{model_identifier}.fmu", FMUS / "fmi3" / f"{model_identifier}.fmu"):
        out = subprocess.run(["cargo", "fmu", "check", "--strict", str(fmu)], cwd=crate, env=env, capture_output=True, text=True,
                             timeout=900)
        summary = [l for l in out.stdout.splitlines() if re.match(r"^\d+ passed, \d+ failed", l)]
        assert out.returncode == 0 and summary and " 0 failed" in summary[-1], out.stdout[-6000:] + out.stderr[-2000:]


PI_CONTROL = '''//! A PI controller, u = kp (r - y) + x with Ti dx/dt = kp (r - y), as a user writes one.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A PI controller
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct PiControl {
    /// Reference r
    #[variable(vr = 0, input, start = 0.0)]
    pub r: f64,
    /// Measurement y
    #[variable(vr = 1, input, start = 0.0)]
    pub y: f64,
    /// Integral part x, the continuous state
    #[variable(vr = 2, output, initial = exact, start = 0.0, depends = [x])]
    pub x: f64,
    /// dx/dt = kp (r - y) / Ti
    #[variable(vr = 3, name = "der(x)", local, derivative_of = x, depends = [r, y], initial_depends = [r, y, kp, Ti])]
    pub der_x: f64,
    /// Command u = kp (r - y) + x
    #[variable(vr = 4, output, depends = [r, y, x], initial_depends = [r, y, x, kp])]
    pub u: f64,
    /// Proportional gain
    #[variable(vr = 5, name = "kp", parameter, tunable, start = 2.0, min > 0.0)]
    pub kp: f64,
    /// Integral time
    #[variable(vr = 6, name = "Ti", parameter, tunable, start = 0.5, unit = "s", min > 0.0)]
    pub ti: f64,
    /// Which loop this is
    #[variable(vr = 7, parameter, start = "loop 1")]
    pub tag: String,
}

impl Model for PiControl {
    fn derivatives<D: Real>(&self, _t: D, v: &mut PiControlContinuous<D>) {
        v.der_x = (v.r - v.y) * self.kp / self.ti;
    }

    fn outputs<D: Real>(&self, _t: D, v: &mut PiControlContinuous<D>) {
        v.u = (v.r - v.y) * self.kp + v.x;
    }
}

impl CoSimulation for PiControl {}

rustfmu::export_fmu!(PiControl);
'''


def test_cargo_fmu_check_passes_on_a_pi_controller_with_positive_parameters_and_a_fixed_string():
    """Issue 23: `cargo fmu check` failed a correct PI controller three times. It set the integral
    time Ti (min > 0, no max) to its bound 5e-324, which makes dx/dt infinite; it excited the
    reference and the measurement alike (r = y: the error is 0 and no gain can matter, "none of
    the tunable parameters changed anything"); and it set the fixed String parameter after
    initialization, where the standard does not allow it. Checked in FMI 2.0 and 3.0."""
    crate, env = outside_crate("pi-control", fresh=True)
    (crate / "src" / "lib.rs").write_text(PI_CONTROL)
    run(["cargo", "fmu", "build"], crate, env)
    check_clean(crate, env, "PiControl")
    # The gains act: the tunable-parameter check found one that changes the trajectory.
    result = fmpy.simulate_fmu(str(FMUS / "PiControl.fmu"), stop_time=1.0, output_interval=0.1,
                               start_values={"r": 1.0, "y": 0.25}, output=["u", "x"])
    assert abs(result["x"][-1] - 2.0 * 0.75 / 0.5) < 1e-9, result["x"][-1]
    assert abs(result["u"][-1] - (2.0 * 0.75 + 3.0)) < 1e-9, result["u"][-1]


MASS_SPRING_DAMPER = '''//! A mass on a spring with a damper, m x'' + c x' + k x = F, as a user writes one.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A mass-spring-damper
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(unit(name = "N.s/m", kg = 1, s = -1), unit(name = "N/m", kg = 1, s = -2))]
pub struct Msd {
    /// External force F
    #[variable(vr = 0, name = "F", input, start = 0.0, unit = "N")]
    pub force: f64,
    /// Position x, a state; its start value is the initial position
    #[variable(vr = 1, output, initial = exact, start = 1.0, unit = "m", depends = [x])]
    pub x: f64,
    /// Velocity v, a state
    #[variable(vr = 2, output, initial = exact, start = 0.0, unit = "m/s", depends = [v])]
    pub v: f64,
    /// dx/dt = v
    #[variable(vr = 3, name = "der(x)", local, unit = "m/s", derivative_of = x, depends = [v], initial_depends = [v])]
    pub der_x: f64,
    /// dv/dt = (F - c v - k x) / m
    #[variable(vr = 4, name = "der(v)", local, unit = "m/s2", derivative_of = v, depends = [F, x, v], initial_depends = [F, x, v, m, c, k])]
    pub der_v: f64,
    /// Spring force k x
    #[variable(vr = 5, output, unit = "N", depends = [x], initial_depends = [x, k])]
    pub spring_force: f64,
    /// Mass m
    #[variable(vr = 6, parameter, tunable, start = 1.0, unit = "kg", min > 0.0)]
    pub m: f64,
    /// Damping c
    #[variable(vr = 7, parameter, tunable, start = 0.4, unit = "N.s/m", min = 0.0)]
    pub c: f64,
    /// Stiffness k
    #[variable(vr = 8, parameter, tunable, start = 4.0, unit = "N/m", min > 0.0)]
    pub k: f64,
}

impl Model for Msd {
    fn derivatives<D: Real>(&self, _t: D, v: &mut MsdContinuous<D>) {
        v.der_x = v.v;
        v.der_v = (v.force - v.v * self.c - v.x * self.k) / self.m;
    }

    fn outputs<D: Real>(&self, _t: D, v: &mut MsdContinuous<D>) {
        v.spring_force = v.x * self.k;
    }
}

impl CoSimulation for Msd {}

rustfmu::export_fmu!(Msd);
'''


def test_a_mass_spring_damper_builds_clean_checks_clean_and_follows_the_exact_solution():
    """Issue 23: the first of the new user's four crates, a mass-spring-damper with every
    dependency declared: `cargo fmu build` finds nothing to note, `cargo fmu check` fails nothing
    in FMI 2.0 and 3.0, and fmpy's co-simulation follows the exact damped oscillation."""
    crate, env = outside_crate("msd", fresh=True)
    (crate / "src" / "lib.rs").write_text(MASS_SPRING_DAMPER)
    out = run(["cargo", "fmu", "build"], crate, env)
    assert "fmu: note:" not in out.stderr, out.stderr[-4000:]
    check_clean(crate, env, "Msd")
    result = fmpy.simulate_fmu(str(FMUS / "Msd.fmu"), stop_time=5.0, output_interval=0.01, output=["x"])
    # x(0) = 1, v(0) = 0, m = 1, c = 0.4, k = 4: x = e^(-0.2 t) (cos wd t + 0.2/wd sin wd t)
    wd = math.sqrt(4.0 - 0.2 ** 2)
    worst = max(abs(x - math.exp(-0.2 * t) * (math.cos(wd * t) + 0.2 / wd * math.sin(wd * t)))
                for t, x in zip(result["time"], result["x"]))
    assert worst < 1e-5, worst


BOUNCING_BALL = '''//! A bouncing ball whose co-simulation step is the exact flight, bounces included.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A ball dropped on a floor, stepped exactly
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Ball {
    /// Height h above the floor
    #[variable(vr = 0, output, discrete, initial = exact, start = 1.0, unit = "m", min = 0.0, depends = [])]
    pub h: f64,
    /// Velocity v, upwards
    #[variable(vr = 1, output, discrete, initial = exact, start = 0.0, unit = "m/s", depends = [])]
    pub v: f64,
    /// Coefficient of restitution e
    #[variable(vr = 2, parameter, fixed, start = 0.8, min = 0.0, max = 1.0)]
    pub e: f64,
    /// Gravity g
    #[variable(vr = 3, parameter, fixed, start = 9.81, unit = "m/s2", min > 0.0)]
    pub g: f64,
}

impl Model for Ball {}

impl CoSimulation for Ball {
    /// The exact ballistic flight over the step, bounce by bounce (h = 0, v -> -e v).
    fn do_step(&mut self, _t: f64, h: f64, _ctx: &mut Context) -> Result<(), StepFailure> {
        let mut left = h;
        while left > 0.0 {
            // The time to the floor: h + v s - g s^2 / 2 = 0.
            let to_floor = (self.v + (self.v * self.v + 2.0 * self.g * self.h).sqrt()) / self.g;
            if to_floor > left || self.v.abs() + self.h < 1e-9 {
                let s = if to_floor > left { left } else { 0.0 };
                self.h = (self.h + self.v * s - 0.5 * self.g * s * s).max(0.0);
                self.v -= self.g * s;
                if to_floor <= left {
                    (self.h, self.v) = (0.0, 0.0);
                }
                break;
            }
            self.v = -self.e * (self.v - self.g * to_floor);
            self.h = 0.0;
            left -= to_floor;
        }
        Ok(())
    }
}

rustfmu::export_fmu!(Ball);
'''


def test_a_bouncing_ball_with_an_exact_step_checks_clean_and_bounces_where_the_formula_says():
    """Issue 23: the second of the new user's crates: no continuous states, its own exact
    `do_step` (the flight and the bounces in closed form). `cargo fmu check` fails nothing in FMI
    2.0 and 3.0 (its excitation of many instances kept inside the height's `min = 0` now), and
    fmpy's co-simulation finds the first bounce at sqrt(2 h0 / g) and the second apex at e^2 h0."""
    crate, env = outside_crate("ball", fresh=True)
    (crate / "src" / "lib.rs").write_text(BOUNCING_BALL)
    out = run(["cargo", "fmu", "build"], crate, env)
    assert "fmu: note:" not in out.stderr, out.stderr[-4000:]
    check_clean(crate, env, "Ball")
    result = fmpy.simulate_fmu(str(FMUS / "Ball.fmu"), fmi_type="CoSimulation", stop_time=2.0, output_interval=0.001,
                               output=["h", "v"])
    t_hit = math.sqrt(2 * 1.0 / 9.81)
    first = next(t for t, v in zip(result["time"], result["v"]) if v > 0)
    assert abs(first - t_hit) <= 0.001 + 1e-9, (first, t_hit)
    # After the first bounce the ball rises with e v_hit to e^2 h0.
    apex = max(h for t, h in zip(result["time"], result["h"]) if t_hit < t < t_hit + 2 * 0.8 * math.sqrt(2 * 9.81) / 9.81)
    assert abs(apex - 0.64) < 1e-5, apex


def sampled_pi_fields(u_doc: str) -> str:
    """The fields of the two sampled PI controllers (SAMPLED_PI samples in its `do_step`, EVENT_PI
    on time events): the same variables; `u_doc` describes the command u."""
    return """    /// Reference r
    #[variable(vr = 0, input, start = 0.0)]
    pub r: f64,
    /// Measurement y
    #[variable(vr = 1, input, start = 0.0)]
    pub y: f64,
    /// """ + u_doc + """
    #[variable(vr = 2, output, discrete, initial = exact, start = 0.0, depends = [])]
    pub u: f64,
    /// Integral part i, held between samples
    #[variable(vr = 3, local, discrete, initial = exact, start = 0.0)]
    pub i: f64,
    /// Proportional gain
    #[variable(vr = 4, parameter, tunable, start = 2.0, min = 0.0, max = 100.0)]
    pub kp: f64,
    /// Integral gain (1/s)
    #[variable(vr = 5, parameter, tunable, start = 1.0, min = 0.0, max = 100.0)]
    pub ki: f64,
    /// Sample period
    #[variable(vr = 6, name = "Ts", parameter, fixed, start = 0.01, unit = "s", min > 0.0)]
    pub ts: f64,
    /// Samples taken
    #[variable(vr = 7, output, discrete, initial = exact, start = 0)]
    pub samples: i32,
"""


SAMPLED_PI = '''//! A PI controller sampled every Ts = 10 ms: at each sample u = kp e + i, then i += ki Ts e.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A sampled PI controller
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct SampledPi {
''' + sampled_pi_fields("Command u, held between samples") + '''}

impl Model for SampledPi {}

impl CoSimulation for SampledPi {
    /// The sample instants k Ts in (t, t + h], with the inputs as they are (held over the step):
    /// the command of the last one, and the integral after all of them.
    fn do_step(&mut self, t: f64, h: f64, _ctx: &mut Context) -> Result<(), StepFailure> {
        let first = (t / self.ts + 1e-9).floor() + 1.0;
        let last = ((t + h) / self.ts + 1e-9).floor();
        if last >= first {
            let n = last - first + 1.0;
            let e = self.r - self.y;
            self.u = self.kp * e + self.i + (n - 1.0) * self.ki * self.ts * e;
            self.i += n * self.ki * self.ts * e;
            self.samples = (f64::from(self.samples) + n).min(f64::from(i32::MAX)) as i32;
        }
        Ok(())
    }
}

rustfmu::export_fmu!(SampledPi);
'''


def test_a_pi_controller_sampled_every_10_ms_checks_clean_and_samples_on_time():
    """Issue 23: the fourth of the new user's crates: a PI controller sampled every 10 ms in its
    own `do_step` (discrete states only). `cargo fmu check` fails nothing in FMI 2.0 and 3.0, and
    in fmpy a step of 25 ms takes the two samples at 10 and 20 ms."""
    crate, env = outside_crate("sampled-pi", fresh=True)
    (crate / "src" / "lib.rs").write_text(SAMPLED_PI)
    out = run(["cargo", "fmu", "build"], crate, env)
    assert "fmu: note:" not in out.stderr, out.stderr[-4000:]
    check_clean(crate, env, "SampledPi")
    result = fmpy.simulate_fmu(str(FMUS / "SampledPi.fmu"), stop_time=0.1, output_interval=0.025,
                               start_values={"r": 1.0}, output=["u", "samples"])
    assert list(result["samples"]) == [0, 2, 5, 7, 10], result
    # u at 25 ms: the second sample, kp e + ki Ts e = 2 + 0.01.
    assert abs(result["u"][1] - 2.01) < 1e-12, result


EVENT_PI = """//! A PI controller sampled every Ts = 10 ms by time events: at each sample u = kp e + i, then i += ki Ts e.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A sampled PI controller on time events
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct EventPi {
""" + sampled_pi_fields("Command u, set at the samples and held between them") + """}

impl Model for EventPi {
    fn update(&mut self, event: &mut Event) -> Result<(), String> {
        if event.time_event() {
            let e = self.r - self.y;
            self.u = self.kp * e + self.i;
            self.i += self.ki * self.ts * e;
            self.samples = self.samples.saturating_add(1);
        }
        // The samples are at k Ts, k = 1, 2, ...: the next one after this event.
        event.schedule(((event.time() / self.ts + 1e-9).floor() + 1.0) * self.ts);
        Ok(())
    }
}

impl CoSimulation for EventPi {}

rustfmu::export_fmu!(EventPi);
"""


def test_a_pi_controller_sampled_by_time_events_is_the_same_in_model_exchange_and_co_simulation():
    """Issue 24: the sampled PI written with the event declarations (`update` at time events, a
    `discrete` output set there). `cargo fmu check` fails nothing in FMI 2.0 and 3.0; the
    reference steps from 0 to 1 at 32.5 ms; in fmpy's Model Exchange (time events at k Ts, CVode)
    and Co-Simulation (5 ms steps, the runtime stepping onto the sample instants) the command at
    every sample instant is the same to the bit, held between the samples, and is
    kp e + ki Ts e (k - 4) from the fourth sample on."""
    crate, env = outside_crate("event-pi", fresh=True)
    (crate / "src" / "lib.rs").write_text(EVENT_PI)
    out = run(["cargo", "fmu", "build"], crate, env)
    assert "fmu: note:" not in out.stderr, out.stderr[-4000:]
    check_clean(crate, env, "EventPi")
    import numpy as np
    signal = np.array([(0.0, 0.0), (0.0325, 0.0), (0.0325, 1.0), (0.1, 1.0)], dtype=[("time", float), ("r", float)])
    runs = {}
    for version, path in (("2.0", FMUS / "EventPi.fmu"), ("3.0", FMUS / "fmi3" / "EventPi.fmu")):
        for kind, kw in (("ME", dict(fmi_type="ModelExchange", output_interval=1e-3)),
                         ("CS", dict(fmi_type="CoSimulation", output_interval=5e-3))):
            runs[version, kind] = fmpy.simulate_fmu(str(path), stop_time=0.1, input=signal, output=["u", "samples"],
                                                    **kw)

    def at_samples(r):
        # The last value recorded at each sample instant (after its event).
        out = []
        for k in range(1, 11):
            i = np.flatnonzero(np.abs(r["time"] - k * 0.01) < 1e-9)
            assert len(i), (k, r["time"])
            out.append((r["u"][i[-1]], r["samples"][i[-1]]))
        return out

    me, cs = at_samples(runs["2.0", "ME"]), at_samples(runs["2.0", "CS"])
    assert me == cs, (me, cs)
    expected = [0.0] * 3 + [2.0 + 0.01 * (k - 4) for k in range(4, 11)]
    assert [u for u, _ in me] == pytest.approx(expected, abs=1e-12)
    assert [n for _, n in me] == list(range(1, 11))
    for kind in ("ME", "CS"):
        a, b = runs["2.0", kind], runs["3.0", kind]
        assert np.array_equal(a["u"], b["u"]) and np.array_equal(a["time"], b["time"]), kind
    # Held between the samples: constant on every (k Ts, (k + 1) Ts).
    r = runs["2.0", "ME"]
    for k in range(10):
        inside = (r["time"] > k * 0.01 + 1e-9) & (r["time"] < (k + 1) * 0.01 - 1e-9)
        assert len(set(r["u"][inside])) <= 1, (k, r["u"][inside])


def test_cargo_fmu_build_refuses_a_depends_that_leaves_out_an_input():
    """Issue 23: a `depends` that misses an input the output uses passed `cargo fmu build` and
    `cargo fmu validate` and was caught only by `cargo fmu check`. The build's smoke run now asks
    the model's exact directional derivatives (dual numbers) at random points and refuses the
    declaration, naming the output and the input; an unknown declared without `depends` (written
    as depending on everything) gets a note with the dependencies found. The same for the
    dependencies at initialization (`initial_depends`, InitialUnknowns): a parameter left out is
    refused, found by moving each known of Initialization Mode on its own."""
    crate, env = outside_crate("pi-wrong-depends", fresh=True)
    src = PI_CONTROL.replace("PiControl", "PiWrongDepends")
    wrong = src.replace("#[variable(vr = 4, output, depends = [r, y, x], initial_depends = [r, y, x, kp])]",
                        "#[variable(vr = 4, output, depends = [r, x], initial_depends = [r, y, x])]")
    wrong = wrong.replace('derivative_of = x, depends = [r, y], initial_depends = [r, y, kp, Ti])]', 'derivative_of = x)]')
    assert wrong.count("depends = [") == 3, wrong
    (crate / "src" / "lib.rs").write_text(wrong)
    out = subprocess.run(["cargo", "fmu", "build"], cwd=crate, env=env, capture_output=True, text=True, timeout=900)
    assert out.returncode != 0, out.stderr
    assert ("output 'u' depends on the input 'y'" in out.stderr and "`depends = [r, x]` leaves out: add 'y'" in out.stderr), \
        out.stderr[-4000:]
    assert ("derivative 'der(x)' declares no `depends`" in out.stderr and "`depends = [r, y]` would say so" in out.stderr), \
        out.stderr[-4000:]
    assert ("initial unknown 'u' depends in Initialization Mode on 'kp'" in out.stderr
            and "`initial_depends = [r, y, x]` leaves out: add 'kp'" in out.stderr), out.stderr[-4000:]
    assert ("initial unknown 'der(x)' declares no `initial_depends`" in out.stderr
            and "`initial_depends = [r, y, kp, Ti]` would say so" in out.stderr), out.stderr[-4000:]
    # The declarations the checks ask for build clean, without a note.
    (crate / "src" / "lib.rs").write_text(src)
    out = run(["cargo", "fmu", "build"], crate, env)
    assert "fmu: note:" not in out.stderr, out.stderr[-4000:]


def test_every_initial_unknown_of_the_project_fmus_lists_its_dependencies():
    """Issue 23: the InitialUnknowns carried no `dependencies`, which the standard reads as
    "depends on every known, the inputs included": OMSimulator saw an algebraic loop through the
    feedthrough Controller at initialization. Every initial unknown of the three FMUs now lists its
    dependencies (declared with `initial_depends`, checked by `cargo fmu build`), in both
    versions; the Pendulum's states depend on their parameters alpha1_0 ... omega2_0 only."""
    import xml.etree.ElementTree as ET
    root = Path(__file__).resolve().parents[2] / "modelDescription"
    for name in ("Pendulum", "Controller", "DCMotor"):
        for version, path in (("2.0", root / f"{name}.xml"), ("3.0", root / "fmi3" / f"{name}.xml")):
            md = ET.parse(path).getroot()
            unknowns = (md.findall("ModelStructure/InitialUnknowns/Unknown") if version == "2.0"
                        else md.findall("ModelStructure/InitialUnknown"))
            assert unknowns, (name, version)
            for u in unknowns:
                assert "dependencies" in u.attrib, (name, version, u.attrib)
    md = ET.parse(root / "Pendulum.xml").getroot()
    variables = md.findall("ModelVariables/ScalarVariable")
    by_index = {str(i + 1): v.get("name") for i, v in enumerate(variables)}
    deps = {by_index[u.get("index")]: sorted(by_index[d] for d in u.get("dependencies").split())
            for u in md.findall("ModelStructure/InitialUnknowns/Unknown")}
    assert deps["alpha1"] == ["alpha1_0"] and deps["omega2"] == ["omega2_0"], deps
    assert deps["der(alpha1)"] == ["omega1_0"], deps
    assert "M1" in deps["der(omega1)"] and "m1" in deps["der(omega1)"], deps


def test_a_python_without_fmpy_is_named_as_such_not_the_fmu_it_was_to_validate(tmp_path):
    """Issue 52, item 6: `--python` naming an interpreter without fmpy printed fmpy's traceback
    and then "error: invalid: PiClock.fmu", blaming a good FMU. Now `cargo fmu validate` and
    `cargo fmu build` say, before anything is judged or built, that the interpreter cannot import
    fmpy, name it and how to install it."""
    import sys

    from conftest import FMU_DIR, fmu3

    bare = tmp_path / "bare"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(bare)], check=True, timeout=300)
    python = bare / "bin" / "python"
    assert subprocess.run([python, "-c", "import fmpy"], capture_output=True).returncode != 0
    cargo_fmu = FMU_DIR.parent / "release" / "cargo-fmu"
    good = fmu3("StateSpace")
    for args in (["validate", "--python", str(python), good], ["build", "--python", str(python)]):
        out = subprocess.run([cargo_fmu, "fmu", *args], cwd=tmp_path, capture_output=True, text=True, timeout=600)
        assert out.returncode != 0, out.stderr
        assert f"--python {python}: this interpreter cannot import fmpy (ModuleNotFoundError: No module named 'fmpy')" \
            in out.stderr, out.stderr
        assert f"`{python} -m pip install fmpy`" in out.stderr, out.stderr
        assert "invalid" not in out.stderr and "Traceback" not in out.stderr, out.stderr
        assert "Compiling" not in out.stderr and "packaged" not in out.stderr, out.stderr
    # The interpreter with fmpy still validates.
    out = subprocess.run([cargo_fmu, "fmu", "validate", "--python", sys.executable, good], capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0 and "is valid" in out.stderr, out.stderr
