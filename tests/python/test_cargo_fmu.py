"""A Rust developer's path from nothing to a validated FMU of their own crate, outside this
workspace, with the `cargo fmu` this workspace builds (target/release/cargo-fmu on PATH is what
`cargo install --path fmu-build` gives): `cargo fmu new`, a change to the model, `cargo fmu
build`, fmpy's validator, `fmpy.simulate_fmu` against the analytic answer, `cargo fmu check`."""

import math
import os
import pathlib
import shutil
import subprocess

import fmpy
import fmpy.validation
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
CARGO_FMU = TARGET / "release" / "cargo-fmu"


def cargo_fmu_env():
    if not CARGO_FMU.exists():
        pytest.fail(f"{CARGO_FMU} is missing: build it with `cargo build --release -p fmu-build --bins`")
    env = dict(os.environ)
    env["PATH"] = f"{CARGO_FMU.parent}{os.pathsep}{env['PATH']}"
    # The new crate has its own target folder, as a user's crate would.
    env.pop("CARGO_TARGET_DIR", None)
    return env


def run(args, cwd, env):
    out = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, f"{' '.join(map(str, args))} failed ({out.returncode}):\n{out.stdout}\n{out.stderr}"
    return out


GAIN_FIELD = '''    /// Gain K of the lag: T dy/dt = K u - y
    #[variable(vr = 4, name = "K", parameter, tunable, start = 1.0, min > 0.0)]
    pub gain: f64,
'''


@pytest.fixture(scope="module")
def user_crate(tmp_path_factory):
    env = cargo_fmu_env()
    where = tmp_path_factory.mktemp("outside")
    run(["cargo", "fmu", "new", "gain-lag"], where, env)
    crate = where / "gain-lag"
    lib = crate / "src" / "lib.rs"
    src = lib.read_text()
    # The user's change: a gain K (tunable, > 0), so that y follows K u.
    assert "pub time_constant: f64,\n}" in src, src
    src = src.replace("pub time_constant: f64,\n}", "pub time_constant: f64,\n" + GAIN_FIELD + "}")
    src = src.replace("self.y = self.u + (self.y - self.u)", "self.y = self.gain * self.u + (self.y - self.gain * self.u)")
    # ... in the equations too (model exchange, directional derivatives).
    assert "v.der_y = (v.u - v.y) / self.time_constant;" in src, src
    src = src.replace("v.der_y = (v.u - v.y) / self.time_constant;", "v.der_y = (v.u * self.gain - v.y) / self.time_constant;")
    lib.write_text(src)
    build = run(["cargo", "fmu", "build"], crate, env)
    fmu = crate / "target" / "fmu" / "GainLag.fmu"
    assert fmu.exists(), build.stderr
    yield crate, fmu, env
    shutil.rmtree(where, ignore_errors=True)


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
    run(["cargo", "fmu", "validate", str(fmu)], crate, env)


def test_cargo_fmu_check_passes_on_it(user_crate):
    crate, fmu, env = user_crate
    out = run(["cargo", "fmu", "check", str(fmu)], crate, env)
    assert " 0 failed" in out.stdout, out.stdout
