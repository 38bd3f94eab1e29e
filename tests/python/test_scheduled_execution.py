"""FMI 3.0 Scheduled Execution (FMI 3.0, chapter 5) in fmpy: the Reference-FMUs' Clocks written
with rustfmu (reference-fmus/clocks) run by a small scheduler written here on fmpy's
FMU3ScheduledExecution, instantiated with a real clockUpdate callback (fmpy's own instantiate
installs a no-op). Over 10 s: inClock1 every second (its interval read with
fmi3GetIntervalDecimal), inClock2 at 0, 1, 8 and 9 (input2 = 7 set before the tick at 8),
inClock3 when the clockUpdate callback says its countdown interval changed; in priority order at
equal times. The callback reads outClock and the counters from inside the activation (Clock
Update Mode). Checked: the counters as the model defines them, outClock's ticks, the description
(fmpy's validator)."""

import ctypes
import heapq
import xml.etree.ElementTree as ET

import fmpy
import fmpy.validation
import pytest
from fmpy.fmi3 import (
    FMU3ScheduledExecution,
    fmi3Boolean,
    fmi3ClockUpdateCallback,
    fmi3InstanceEnvironment,
    fmi3LockPreemptionCallback,
    fmi3LogMessageCallback,
    fmi3UnlockPreemptionCallback,
)

from conftest import fmu3

STOP = 10.0


@pytest.fixture(scope="module")
def clocks():
    path = fmu3("Clocks")
    md = fmpy.read_model_description(path)
    return path, md, fmpy.extract(path)


def test_the_description_declares_scheduled_execution_and_priorities(clocks):
    path, md, _ = clocks
    assert fmpy.validation.validate_fmu(path) == []
    assert md.scheduledExecution is not None
    assert md.scheduledExecution.modelIdentifier == "Clocks"
    prio = {name: p for name, p in priorities(clocks).items()}
    assert prio == {"inClock1": 0, "inClock2": 1, "inClock3": 2, "outClock": 2}
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    assert vrs["inClock1"] == 1001 and vrs["outClock"] == 1005 and vrs["output3"] == 2007


def priorities(clocks):
    """Each Clock's `priority` (fmpy 0.3.32 does not read it), by name."""
    _, _, unzipped = clocks
    root = ET.parse(f"{unzipped}/modelDescription.xml").getroot()
    return {c.get("name"): int(c.get("priority")) for c in root.iter("Clock")}


class Scheduled(FMU3ScheduledExecution):
    """fmpy's class, instantiated with a clockUpdate callback that calls `on_clock_update`."""

    def instantiate_with(self, on_clock_update, messages):
        def log(env, status, category, message):
            messages.append((status, message.decode()))

        def update(env):
            on_clock_update()

        # Kept from the garbage collector as long as the instance lives.
        self.logMessage = fmi3LogMessageCallback(log)
        self.clockUpdate = fmi3ClockUpdateCallback(update)
        self.lockPreemption = fmi3LockPreemptionCallback(lambda: None)
        self.unlockPreemption = fmi3UnlockPreemptionCallback(lambda: None)
        self.component = self.fmi3InstantiateScheduledExecution(
            self.instanceName.encode(),
            self.guid.encode(),
            (str(self.unzipDirectory) + "/resources/").encode(),
            fmi3Boolean(False),
            fmi3Boolean(False),
            fmi3InstanceEnvironment(),
            self.logMessage,
            self.clockUpdate,
            self.lockPreemption,
            self.unlockPreemption,
        )
        assert self.component, messages


def interval(fmu, vr):
    h, q = (ctypes.c_double * 1)(), (ctypes.c_int * 1)()
    fmu.getIntervalDecimal((ctypes.c_uint * 1)(vr), h, q)
    return h[0], q[0]


def test_a_scheduler_runs_the_partitions_and_hears_of_the_clocks(clocks):
    path, md, unzipped = clocks
    vr = {v.name: v.valueReference for v in md.modelVariables}
    prio = {vr[name]: p for name, p in priorities(clocks).items()}
    fmu = Scheduled(guid=md.guid, unzipDirectory=unzipped,
                    modelIdentifier=md.scheduledExecution.modelIdentifier, instanceName="clocks")
    queue, now, out_ticks, updates, messages = [], [0.0], [], [], []

    def schedule(t, clock):
        if t < STOP:
            heapq.heappush(queue, (t, prio[clock], clock))

    def on_clock_update():
        # Clock Update Mode: the activation's results are read from inside it.
        t = now[0]
        (ticked,) = fmu.getClock([vr["outClock"]])
        if ticked:
            out_ticks.append((t, fmu.getInt32([vr["totalInClockTicks"]])[0]))
        h, q = interval(fmu, vr["inClock3"])
        if q == 2:  # fmi3IntervalChanged
            schedule(t + h, vr["inClock3"])
        updates.append(t)

    fmu.instantiate_with(on_clock_update, messages)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    h1, q1 = interval(fmu, vr["inClock1"])
    assert (h1, q1) == (1.0, 1)  # constant: fmi3IntervalUnchanged
    for k in range(int(STOP / h1)):
        schedule(k * h1, vr["inClock1"])
    for t in (0.0, 1.0, 8.0, 9.0):
        schedule(t, vr["inClock2"])
    activations = []
    while queue:
        t, _, clock = heapq.heappop(queue)
        if clock == vr["inClock2"] and t == 8.0:
            fmu.setInt32([vr["input2"]], [7])
        now[0] = t
        fmu.activateModelPartition(clock, t)
        activations.append((t, clock))
    got = dict(zip(
        ["inClock1Ticks", "inClock2Ticks", "inClock3Ticks", "totalInClockTicks", "result2", "output3"],
        fmu.getInt32([vr[n] for n in ["inClock1Ticks", "inClock2Ticks", "inClock3Ticks",
                                       "totalInClockTicks", "result2", "output3"]]),
    ))
    fmu.terminate()
    fmu.freeInstance()
    # The model: inClock1 ticks 10 times, inClock2 4 times, inClock3 once (0.5 s after inClock1's
    # tick at 4, which gives it its interval); result2 adds input2 = 7 at 8; output3 = 1000.
    assert got == dict(inClock1Ticks=10, inClock2Ticks=4, inClock3Ticks=1, totalInClockTicks=15,
                       result2=7, output3=1000), messages
    assert (4.5, vr["inClock3"]) in activations
    # outClock ticks where the total reaches 5, 10 and 15: inClock1 at 2 (1+1, 1+1, 1), inClock1 at
    # 6 (after 3, 4, 4.5, 5), inClock2 at 9 (inClock1 before it: priority 0 before 1).
    assert out_ticks == [(2.0, 5), (6.0, 10), (9.0, 15)]
    # The callback was called for those and for the countdown interval at 4, nothing else.
    assert updates == [2.0, 4.0, 6.0, 9.0]
    assert not [m for s, m in messages if s >= 3], messages


def test_model_exchange_functions_are_refused_and_activation_checks_its_clock(clocks):
    path, md, unzipped = clocks
    vr = {v.name: v.valueReference for v in md.modelVariables}
    messages = []
    fmu = Scheduled(guid=md.guid, unzipDirectory=unzipped,
                    modelIdentifier=md.scheduledExecution.modelIdentifier, instanceName="clocks")
    fmu.instantiate_with(lambda: None, messages)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    with pytest.raises(Exception):
        fmu.activateModelPartition(vr["outClock"], 0.0)
    assert any("is an output Clock" in m for _, m in messages), messages
    # The refusal ended the run (FMI 3.0: Terminated); after fmi3Reset, a model-exchange call.
    fmu.reset()
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    with pytest.raises(Exception):
        fmu.fmi3EnterEventMode(fmu.component)
    assert any("instantiated for scheduled execution" in m for _, m in messages), messages
    fmu.freeInstance()
