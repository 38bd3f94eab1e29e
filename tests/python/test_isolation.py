"""Isolation in the native runner (issue 26): `System(path, isolate=True)` runs each component in
a child process of its own (runner/src/isolate.rs). An FMU that crashes (a segmentation fault),
aborts, exits or hangs fails the run with an FmiError naming the component, the FMI function and
the time; the runner (this Python process, a Dask worker) lives on, and the next run starts the
components anew. The crashing FMU is a test FMU made here (`cargo fmu build` of a crate outside
the workspace), not shipped."""

import subprocess
import zipfile

import numpy as np
import pytest
from conftest import FMU_DIR, USER_TARGET, outside_crate

import rustfmu_runner

CRASHER = '''//! A test FMU that fails on purpose at the first step that ends after `crash_at` (never shipped).
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// y integrates 1 + u; at the step past crash_at: how = 1 a segmentation fault, 2 abort(),
/// 3 exit(3), 4 a hang, else fmi2Discard
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Crasher {
    /// Input u
    #[variable(vr = 0, input, start = 0.0)]
    pub u: f64,
    /// Output y
    #[variable(vr = 1, output, discrete, initial = exact, start = 0.0, depends = [])]
    pub y: f64,
    /// Time after which a step fails
    #[variable(vr = 2, parameter, fixed, start = 1.0e9, unit = "s")]
    pub crash_at: f64,
    /// How it fails
    #[variable(vr = 3, parameter, fixed, start = 1)]
    pub how: i32,
}

impl Model for Crasher {}

impl CoSimulation for Crasher {
    fn do_step(&mut self, t: f64, h: f64, _ctx: &mut Context) -> Result<(), StepFailure> {
        if t + h > self.crash_at {
            match self.how {
                // SAFETY: none; this FMU exists to crash its host.
                1 => unsafe { std::ptr::null_mut::<f64>().write_volatile(1.0) },
                2 => std::process::abort(),
                3 => std::process::exit(3),
                4 => loop {
                    std::thread::sleep(std::time::Duration::from_secs(1))
                },
                _ => {
                    return Err(StepFailure {
                        reached_time: t,
                        message: format!("failed on purpose at t = {t}"),
                    });
                }
            }
        }
        self.y += h * (1.0 + self.u);
        Ok(())
    }
}

rustfmu::export_fmu!(Crasher);
'''

SSD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0" name="Crash">
  <ssd:System name="Crash">
    <ssd:Elements>
      <ssd:Component name="steady" source="resources/Crasher.fmu" type="application/x-fmu-sharedlibrary"/>
      <ssd:Component name="crasher" source="resources/Crasher.fmu" type="application/x-fmu-sharedlibrary"/>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="steady" startConnector="y" endElement="crasher" endConnector="u"/>
    </ssd:Connections>
  </ssd:System>
</ssd:SystemStructureDescription>"""


@pytest.fixture(scope="module")
def crash_ssp(tmp_path_factory):
    crate, env = outside_crate("crasher", fresh=True)
    (crate / "src" / "lib.rs").write_text(CRASHER)
    out = subprocess.run(["cargo", "fmu", "build", "--fmi-version", "2"], cwd=crate, env=env, capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stderr[-4000:]
    fmu = USER_TARGET / "fmu" / "Crasher.fmu"
    path = tmp_path_factory.mktemp("isolation") / "Crash.ssp"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("SystemStructure.ssd", SSD)
        z.writestr("resources/Crasher.fmu", fmu.read_bytes())
    return str(path)


def expect_failure(system, start, match):
    with pytest.raises(rustfmu_runner.FmuError) as e:
        system.run(1.0, 0.01, start=start)
    assert e.value.component == "crasher", str(e.value)
    assert e.value.function == "fmi2DoStep", str(e.value)
    # The step that crosses crash_at = 0.5 s starts at 0.5 - 0.01 < t <= 0.5.
    assert 0.48 < e.value.time <= 0.5, str(e.value)
    assert match in str(e.value), str(e.value)
    return e.value


@pytest.mark.parametrize("granularity", ["component", "system"])
@pytest.mark.parametrize(
    "how, match",
    [
        (1, "died of signal 11 (SIGSEGV, a segmentation fault)"),
        (2, "died of signal 6 (SIGABRT, an abort)"),
        (3, "exited with status 3"),
    ],
)
def test_a_crashing_fmu_fails_the_run_with_component_function_and_time_and_the_runner_lives_on(crash_ssp, how, match, granularity):
    """Segmentation fault, abort(), exit(3) in fmi2DoStep at t = 0.5 s: an FmuError with the
    component, fmi2DoStep and the step's time; the same System then runs again, the crashed
    process replaced, and equals an in-process run. Each FMU in a process of its own, or the
    whole system in one (the component found from the last call the child made)."""
    system = rustfmu_runner.System(crash_ssp, isolate=granularity)
    err = expect_failure(system, {"crasher.crash_at": 0.5, "crasher.how": how}, match)
    owner = "component 'crasher'" if granularity == "component" else "the system"
    assert "did not return" in str(err) and f"the process of {owner}" in str(err), str(err)
    assert err.status == "Fatal"
    again = system.run(1.0, 0.01)
    here = rustfmu_runner.System(crash_ssp).run(1.0, 0.01)
    for k in here:
        assert np.array_equal(again[k], here[k]), k


@pytest.mark.parametrize("granularity", ["component", "system"])
def test_a_hanging_fmu_is_killed_after_the_call_timeout(crash_ssp, granularity):
    system = rustfmu_runner.System(crash_ssp, isolate=granularity, call_timeout=0.5)
    expect_failure(system, {"crasher.crash_at": 0.5, "crasher.how": 4}, "did not return within 0.5 s")
    assert system.run(0.2, 0.01)["crasher.y"][-1] > 0


def test_an_fmi_failure_of_an_isolated_component_is_reported_as_in_process(crash_ssp):
    """fmi2DoStep's status comes back with the next call (the step is not waited for): the
    error still names fmi2DoStep, its time and status, and the FMU's own message, as in-process."""
    start = {"crasher.crash_at": 0.5, "crasher.how": 5}
    errors = []
    for isolate in (False, "component", "system"):
        with pytest.raises(rustfmu_runner.FmuError) as e:
            rustfmu_runner.System(crash_ssp, isolate=isolate).run(1.0, 0.01, start=start)
        errors.append(e.value)
    for err in errors:
        assert (err.component, err.function, err.status) == ("crasher", "fmi2DoStep", "Discard"), str(err)
        assert "failed on purpose" in str(err), str(err)
        assert err.time == errors[0].time
    # The whole system's child runs the in-process master: the same error, word for word.
    assert str(errors[2]) == str(errors[0])


@pytest.mark.parametrize("granularity", ["component", "system"])
@pytest.mark.parametrize("name", ["PendulumLQR", "PendulumMotors"])
def test_isolated_components_give_the_in_process_result_bit_for_bit(name, granularity):
    """Every output of both systems, 2 s at 1 ms; with FMU state, rollback (tolerance=) and the
    first-order hold too."""
    path = str(FMU_DIR / f"{name}.ssp")
    here, there = rustfmu_runner.System(path), rustfmu_runner.System(path, isolate=granularity)
    assert (there.outputs, there.components, there.evaluation_order) == (here.outputs, here.components, here.evaluation_order)
    for kwargs in ({}, {"tolerance": 1e-3}, {"input_derivatives": True}):
        a, b = here.run(2.0, 1e-3, **kwargs), there.run(2.0, 1e-3, **kwargs)
        assert a.keys() == b.keys()
        for k in a:
            assert np.array_equal(a[k], b[k]), (kwargs, k)


def test_isolation_options_are_checked():
    path = str(FMU_DIR / "PendulumLQR.ssp")
    with pytest.raises(ValueError, match="call_timeout"):
        rustfmu_runner.System(path, isolate=True, call_timeout=-1.0)
    with pytest.raises(ValueError, match="isolate=True"):
        rustfmu_runner.System(path, call_timeout=1.0)
    with pytest.raises(ValueError, match="component"):
        rustfmu_runner.System(path, isolate="everything")
    with pytest.raises(rustfmu_runner.VariableError, match="not a file"):
        rustfmu_runner.System(path, isolate=True, worker="/nonexistent/rustfmu-runner")


def test_the_command_line_isolates_too(crash_ssp, tmp_path):
    runner = FMU_DIR.parent / "release" / "rustfmu-runner"
    r = subprocess.run(
        [runner, "run", crash_ssp, "--stop-time", "1", "--step", "0.01", "--isolate", "--no-progress",
         "--set", "crasher.crash_at=0.5", "--set", "crasher.how=1", "-o", tmp_path / "out.csv"],
        capture_output=True, text=True, timeout=120,
    )
    assert r.returncode == 1
    assert "component 'crasher': fmi2DoStep at t = 0.5 s did not return" in r.stderr and "SIGSEGV" in r.stderr, r.stderr


def _run_crash_system(ssp, how):
    """A Dask task: the crash system, isolated, in the worker; returns (pid, error text)."""
    import os

    import rustfmu_runner as rf

    try:
        rf.System(ssp, isolate=True).run(1.0, 0.01, start={"crasher.crash_at": 0.5, "crasher.how": how})
        return os.getpid(), None
    except rf.FmuError as e:
        return os.getpid(), str(e)


def test_a_dask_worker_lives_on_when_an_isolated_fmu_crashes(crash_ssp):
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, Client(cluster) as client:
        pid1, err1 = client.submit(_run_crash_system, crash_ssp, 1, pure=False).result(timeout=120)
        pid2, err2 = client.submit(_run_crash_system, crash_ssp, 2, pure=False).result(timeout=120)
        pid3, err3 = client.submit(_run_crash_system, crash_ssp, 5, pure=False).result(timeout=120)
    assert "SIGSEGV" in err1 and "SIGABRT" in err2 and "failed on purpose" in err3, (err1, err2, err3)
    assert pid1 == pid2 == pid3, "the worker was restarted"


@pytest.mark.parametrize("master", ["isolated", "isolated-system"])
def test_the_parameter_study_with_isolated_fmus_gives_the_in_process_rows(tmp_path, master):
    """examples/parameter_study.py --master isolated / isolated-system: the small study of test_parameter_study on a
    LocalCluster of two workers, each FMU in a child process: the rows of the in-process runs (the
    failed run's FMI status, function and the FMU's message too)."""
    import pandas as pd
    from test_parameter_study import COMPARED, paths, runner, small_study

    here = runner.run_sequential(small_study(), paths(), fresh=True, out=tmp_path / "here.csv")
    assert here
    report = runner.run_study(small_study(), tmp_path / "isolated.csv", paths(), n_workers=2, threads_per_worker=1, progress=False, master=master)
    assert report.executed == len(small_study()), str(report)
    a = pd.read_csv(tmp_path / "here.csv").set_index("run_id").sort_index()
    b = pd.read_csv(tmp_path / "isolated.csv").set_index("run_id").sort_index()
    assert list(a.index) == list(b.index)
    assert set(b["master"]) == {master}
    for c in COMPARED:
        if c == "error":
            continue
        for rid, x, y in zip(a.index, a[c], b[c]):
            assert x == y or (isinstance(x, float) and isinstance(y, float) and np.isnan(x) and np.isnan(y)), (c, rid, x, y)
    failed = b[b["status"] == "failed"]
    assert len(failed) == 1 and "-0.5 for 'm1' (vr 20) is outside (0, inf)" in failed["error"].iloc[0], failed["error"].to_dict()


def _children_of(pid):
    kids = []
    for p in __import__("pathlib").Path("/proc").iterdir():
        if p.name.isdigit():
            try:
                fields = (p / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                kids.append(int(p.name))
    return kids


@pytest.mark.parametrize("granularity", ["component", "system"])
def test_the_children_end_when_the_runner_is_killed(granularity, tmp_path):
    """A runner killed (SIGKILL: no destructor runs) leaves no child behind: each child watches its
    parent and ends within 100 ms of it, also from inside an FMU call that hangs."""
    import os
    import signal
    import sys
    import time

    script = tmp_path / "runner.py"
    script.write_text(
        "import sys, time, rustfmu_runner\n"
        f"s = rustfmu_runner.System({str(FMU_DIR / 'PendulumLQR.ssp')!r}, isolate={granularity!r})\n"
        "s.run(0.1, 1e-3)\n"
        "print('ready', flush=True)\n"
        "time.sleep(60)\n"
    )
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "ready"
        kids = _children_of(p.pid)
        assert len(kids) == (2 if granularity == "component" else 1), kids
    finally:
        os.kill(p.pid, signal.SIGKILL)
        p.wait()
    def running(k):
        try:
            return open(f"/proc/{k}/stat").read().rsplit(")", 1)[1].split()[0] != "Z"
        except OSError:
            return False

    deadline = time.time() + 5
    while time.time() < deadline and any(running(k) for k in kids):
        time.sleep(0.05)
    alive = [k for k in kids if running(k)]
    assert not alive, f"children {alive} outlived the runner"
