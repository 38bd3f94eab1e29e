"""FMI 3.0 Scheduled Execution components in the native runner (issue 54; runner/README.md,
"Scheduled Execution"), run by the rustfmu-runner command line from SSP files written here,
against fmpy driving the same FMUs:

- the C Reference-FMUs' Clocks (Scheduled Execution only; fmusim cannot run it: "No supported
  interface type found"), 10 s, against a scheduler on fmpy's FMU3ScheduledExecution written
  here (inClock1 every second, inClock3 when the clockUpdate callback says its countdown
  interval changed, in priority order at one time): every counter equal at every second;
- the SampledController with `implementation="ScheduledExecution"` closing the PendulumLQR loop
  with the Pendulum, 2 s, against the tests' own fmpy scheduler (examples/cosim/master.py, the
  controller in event-mode co-simulation): every recorded variable equal at every
  communication point, bit for bit."""

import csv
import heapq
import pathlib
import sys
import xml.etree.ElementTree as ET
import zipfile

import fmpy
import numpy as np
import pytest
from conftest import ROOT, fmu3
from test_runner import cli
from test_scheduled_execution import Scheduled, interval

sys.path.insert(0, str(ROOT / "examples"))
from cosim.master import simulate  # noqa: E402
from cosim.systems import Component, Connection, System  # noqa: E402

CLOCKS_C = ROOT.parent / "shared/independent/reference-fmus/3.0/Clocks.fmu"
COUNTERS = ["inClock1Ticks", "inClock2Ticks", "inClock3Ticks", "totalInClockTicks", "result2", "output3"]


def ssp(tmp_path: pathlib.Path, name: str, components, connections=()) -> str:
    """An SSP 2.0 file of `components` (name, FMU file, implementation) and data `connections`."""
    elements = "".join(
        f'<ssd:Component name="{c}" source="resources/{pathlib.Path(f).name}" '
        f'type="application/x-fmu-sharedlibrary" implementation="{impl}"/>'
        for c, f, impl in components
    )
    conns = "".join(
        f'<ssd:Connection startElement="{a}" startConnector="{x}" endElement="{b}" endConnector="{y}"/>'
        for a, x, b, y in connections
    )
    conns = f"<ssd:Connections>{conns}</ssd:Connections>" if conns else ""
    ssd = f"""<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
  xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="2.0" name="{name}">
<ssd:System name="{name}"><ssd:Elements>{elements}</ssd:Elements>
{conns}</ssd:System></ssd:SystemStructureDescription>"""
    out = tmp_path / f"{name}.ssp"
    with zipfile.ZipFile(out, "w") as z:
        z.writestr("SystemStructure.ssd", ssd)
        for _, f, _ in components:
            z.write(f, f"resources/{pathlib.Path(f).name}")
    return str(out)


def run_cli(path, stop, step, record, *extra) -> dict:
    out = path + ".csv"
    args = ["run", path, "--stop-time", stop, "--step", step, "--no-progress", "-o", out, *extra]
    args += [x for r in record for x in ("--record", r)]
    r = cli(*args)
    assert r.returncode == 0, r.stderr
    with open(out) as f:
        rows = list(csv.reader(f))
    data = np.array(rows[1:], dtype=float)
    return {k: data[:, i] for i, k in enumerate(rows[0])}


def clocks_by_fmpy(stop: float) -> dict:
    """The C Clocks run by a scheduler on fmpy: its counters after each time's activations."""
    md = fmpy.read_model_description(str(CLOCKS_C))
    unzipped = fmpy.extract(str(CLOCKS_C))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    prio = {vr["inClock1"]: 0, vr["inClock2"]: 1, vr["inClock3"]: 2}
    fmu = Scheduled(guid=md.guid, unzipDirectory=unzipped,
                    modelIdentifier=md.scheduledExecution.modelIdentifier, instanceName="clocks")
    queue, now, messages = [], [0.0], []

    def on_clock_update():
        fmu.getClock([vr["outClock"]])
        h, q = interval(fmu, vr["inClock3"])
        if q == 2:  # fmi3IntervalChanged
            heapq.heappush(queue, (now[0] + h, prio[vr["inClock3"]], vr["inClock3"]))

    fmu.instantiate_with(on_clock_update, messages)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    # inClock1 is constant: its interval is the description's (this binary answers
    # fmi3GetIntervalDecimal for inClock3 only).
    root = ET.parse(f"{unzipped}/modelDescription.xml").getroot()
    h1 = float(next(c for c in root.iter("Clock") if c.get("name") == "inClock1").get("intervalDecimal"))
    for k in range(int(round(stop / h1)) + 1):
        heapq.heappush(queue, (k * h1, prio[vr["inClock1"]], vr["inClock1"]))
    rows = {}
    while queue:
        t, _, clock = heapq.heappop(queue)
        now[0] = t
        fmu.activateModelPartition(clock, t)
        if not queue or queue[0][0] > t:
            rows[t] = fmu.getInt32([vr[n] for n in COUNTERS])
    fmu.terminate()
    fmu.freeInstance()
    assert not [m for s, m in messages if s >= 3], messages
    return rows


def test_the_reference_clocks_in_the_runner_equals_an_fmpy_scheduler_at_every_second(tmp_path):
    assert CLOCKS_C.exists(), f"{CLOCKS_C} is missing (the C Reference-FMUs v0.0.41 of shared/independent)"
    # Scheduled Execution is Clocks' only interface: "any" gets it, as "ScheduledExecution" does.
    for impl in ["any", "ScheduledExecution"]:
        path = ssp(tmp_path, f"Clocks_{impl}", [("clocks", CLOCKS_C, impl)])
        got = run_cli(path, "10", "1", [f"clocks.{n}" for n in COUNTERS])
        want = clocks_by_fmpy(10.0)
        assert list(got["time"]) == sorted(want), got["time"]
        for k, t in enumerate(got["time"]):
            assert [got[f"clocks.{n}"][k] for n in COUNTERS] == want[t], (impl, t)
        # Something happened: inClock3's countdown ticked once, at 4 s.
        assert want[10.0][COUNTERS.index("inClock3Ticks")] == 1


def test_a_component_without_scheduled_execution_asked_to_run_so_is_refused_naming_it(tmp_path):
    path = ssp(tmp_path, "Plant", [("plant", fmu3("Pendulum"), "ScheduledExecution")])
    r = cli("run", path, "--stop-time", "0.01", "--step", "0.001", "--no-progress", "-o", path + ".csv")
    assert r.returncode != 0
    assert ("component 'plant' (Pendulum): no Scheduled Execution: its modelDescription.xml has no "
            "<ScheduledExecution>") in r.stderr, r.stderr


LOOP = [
    ("pendulum", "alpha1", "controller", "alpha1"),
    ("pendulum", "omega1", "controller", "omega1"),
    ("pendulum", "alpha2", "controller", "alpha2"),
    ("pendulum", "omega2", "controller", "omega2"),
    ("controller", "M1", "pendulum", "M1"),
    ("controller", "M2", "pendulum", "M2"),
]
START = {"pendulum": {"alpha1_0": 0.1, "alpha2_0": -0.05}, "controller": {"mode": 1}}


@pytest.mark.parametrize("step", [0.01, 0.005], ids=["h=Ts", "h=Ts/2"])
def test_the_sampled_controller_in_scheduled_execution_closes_the_loop_as_the_fmpy_scheduler(step, tmp_path):
    pendulum, controller = fmu3("Pendulum"), fmu3("SampledController")
    path = ssp(tmp_path, "PendulumLQRScheduled",
               [("pendulum", pendulum, "CoSimulation"), ("controller", controller, "ScheduledExecution")], LOOP)
    record = {"pendulum": ["alpha1", "omega1", "alpha2", "omega2"], "controller": ["M1", "M2"]}
    sets = [x for c, vs in START.items() for v, x0 in vs.items() for x in ("--set", f"{c}.{v}={x0}")]
    got = run_cli(path, "2", str(step), [f"{c}.{v}" for c, vs in record.items() for v in vs], *sets)
    system = System("PendulumLQR",
                    (Component("pendulum", pendulum, START["pendulum"]),
                     Component("controller", controller, START["controller"])),
                    tuple(Connection(*k) for k in LOOP))
    want = simulate(system, 2.0, step, record)
    assert np.array_equal(got["time"], want["time"])
    for key in want:
        assert np.array_equal(got[key], want[key]), (key, np.max(np.abs(got[key] - want[key])))
    assert np.max(np.abs(got["controller.M1"])) > 0.1
    assert abs(got["pendulum.alpha1"][-1]) < abs(got["pendulum.alpha1"][0])


def test_the_python_module_runs_the_scheduled_component_as_the_command_line(tmp_path):
    import rustfmu_runner

    path = ssp(tmp_path, "PendulumLQRScheduled",
               [("pendulum", fmu3("Pendulum"), "CoSimulation"),
                ("controller", fmu3("SampledController"), "ScheduledExecution")], LOOP)
    record = ["pendulum.alpha1", "pendulum.omega1", "controller.M1", "controller.M2"]
    sets = [x for c, vs in START.items() for v, x0 in vs.items() for x in ("--set", f"{c}.{v}={x0}")]
    want = run_cli(path, "1", "0.005", record, *sets)
    start = {f"{c}.{v}": x0 for c, vs in START.items() for v, x0 in vs.items()}
    got = rustfmu_runner.System(path).run(1.0, 0.005, record=record, start=start)
    for key in want:
        assert np.array_equal(np.asarray(got[key]), want[key]), key
    # Each component in a child process of its own: the same rows.
    isolated = rustfmu_runner.System(path, isolate="component").run(1.0, 0.005, record=record, start=start)
    for key in want:
        assert np.array_equal(np.asarray(isolated[key]), want[key]), key
