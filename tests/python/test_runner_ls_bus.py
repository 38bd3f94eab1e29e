"""An FMI-LS-BUS CAN network in the runner, against the same network run by fmpy with a scheduler
written here: two CanSignal nodes (holonomic/fmus/can_signal) on ports 1 and 2 of the CanBus bus
simulation (holonomic/fmus/can_bus), each node's signal u from a VanDerPol oscillator, in an SSP
2.0 file whose clock connections join each node's Tx_Clock to its port's Rx_Clock and the port's
Tx_Clock to the node's Rx_Clock (FMI-LS-BUS 1.0.0, Time-based Tx Clocks: the node's countdown
Tx_Clock and the bus's triggered Rx_Clock are connected, the bus's countdown Tx_Clock and the
node's triggered Rx_Clock).

The scheduler (`schedule`) is the importer the layered standard describes ("the importer can
adapt the next communicationStepSize for all networked FMUs accordingly"), over the same fixed
grid as the runner: every FMU steps to the earliest announced Tx tick (each countdown's interval
read after each event) or the next grid point; at a tick a node's Tx_Data is handed to its port's
Rx_Data and the port's Tx_Data to its node's Rx_Data; what each FMU gives after the event is
recorded. Every byte it hands on is kept, and each delivered CAN Transmit is decoded with `struct`
from the standard's table (test_ls_bus_can's helpers), so that the frames the runner carried are
checked against the scheduler's bytes: timestamps, payloads, Confirms."""

import math
import struct

import fmpy
import numpy as np
import pytest
from fmpy.fmi3 import FMU3Slave, fmi3Float64, fmi3IntervalQualifier, fmi3ValueReference

from conftest import fmu3
from test_ls_bus_can import Bus, Node, operations, transmitted
from test_runner import cli
from test_runner_fmi3_types import runner
from test_ssp2 import valid, write_ssp2

PERIOD = 0.01
STEP = 0.01
NODES = {"sensor": dict(tx_id=0x123, rx_id=0x200, port=1, source="x0"),
         "actuator": dict(tx_id=0x200, rx_id=0x123, port=2, source="x1")}
RECORD = [f"{n}.{v}" for n in NODES for v in ("y", "frames_sent", "frames_received", "confirmed", "arbitration_lost",
                                              "bus_errors")] + \
         [f"bus.{v}" for v in ("bus_load", "frames_delivered", "bus_errors", "arbitration_losses")] + ["vdp.x0", "vdp.x1"]


def network_ssp(tmp_path, error_every, leave_out=()):
    """The SSP 2.0 file of the network (VanDerPol first: the nodes' u are set before their Tx_Data
    is read, which CanSignal's ModelStructure does not order), without the connections
    `leave_out` [(a, out, b, in)]."""
    comps = [("vdp", fmu3("VanDerPol"))] + [(n, fmu3("CanSignal")) for n in NODES] + [("bus", fmu3("CanBus"))]
    connectors = {"vdp": [("x0", "output", "Float64", ()), ("x1", "output", "Float64", ())], "bus": []}
    connections, parameters = [], {"bus": [("error_every", "Int32", error_every, ())]}
    for n, d in NODES.items():
        p = d["port"]
        connectors[n] = [("u", "input", "Float64", ()), ("CAN.Tx_Clock", "input", "Clock", ()),
                         ("CAN.Tx_Data", "output", "Binary", ()), ("CAN.Rx_Clock", "input", "Clock", ()),
                         ("CAN.Rx_Data", "input", "Binary", ())]
        connectors["bus"] += [(f"Node{p}.Rx_Clock", "input", "Clock", ()), (f"Node{p}.Rx_Data", "input", "Binary", ()),
                              (f"Node{p}.Tx_Clock", "input", "Clock", ()), (f"Node{p}.Tx_Data", "output", "Binary", ())]
        connections += [("vdp", d["source"], n, "u"),
                        (n, "CAN.Tx_Clock", "bus", f"Node{p}.Rx_Clock"), (n, "CAN.Tx_Data", "bus", f"Node{p}.Rx_Data"),
                        ("bus", f"Node{p}.Tx_Clock", n, "CAN.Rx_Clock"), ("bus", f"Node{p}.Tx_Data", n, "CAN.Rx_Data")]
        parameters[n] = [("tx_id", "Int32", d["tx_id"], ()), ("rx_id", "Int32", d["rx_id"], ()),
                         ("period", "Float64", PERIOD, ()), ("BusNotifications", "Boolean", "true", ())]
    connections = [c for c in connections if c not in leave_out]
    path, ssd = write_ssp2(tmp_path / "CanNetwork.ssp", comps, connectors, connections, parameters)
    valid(ssd)
    return path


def test_a_clocked_binary_without_the_clock_connection_of_its_clocks_is_refused(tmp_path):
    """A file written by others: the sensor's Tx_Data into the bus's Rx_Data without the Tx_Clock
    -> Rx_Clock connection (the bus's triggered Rx_Clock would never tick, Rx_Data never be set)
    is refused naming both variables and the clock connection, as `cargo fmu build` refuses it."""
    path = network_ssp(tmp_path, 0, leave_out=[("sensor", "CAN.Tx_Clock", "bus", "Node1.Rx_Clock")])
    r = cli("run", path, "--stop-time", "0.1", "--step", STEP, "--no-progress")
    assert r.returncode == 1, r.stdout + r.stderr
    assert "connection sensor.CAN.Tx_Data -> bus.Node1.Rx_Data: sensor.CAN.Tx_Data is clocked by sensor.CAN.Tx_Clock" \
        in r.stderr and "without the clock connection sensor.CAN.Tx_Clock -> bus.Node1.Rx_Clock" in r.stderr, r.stderr


def tx_interval(node):
    """The node's countdown Tx_Clock: (interval, qualifier) read after an event."""
    vrs = (fmi3ValueReference * 1)(node.vr["CAN.Tx_Clock"])
    intervals, qualifiers = (fmi3Float64 * 1)(), (fmi3IntervalQualifier * 1)()
    node.f.getIntervalDecimal(vrs, intervals, qualifiers)
    return intervals[0], qualifiers[0]


def schedule(stop, error_every):
    """The network in fmpy (see the module): the recorded rows and the bytes delivered,
    [(time, port, bytes)]."""
    md = fmpy.read_model_description(fmu3("VanDerPol"))
    vdp = FMU3Slave(guid=md.guid, unzipDirectory=fmpy.extract(fmu3("VanDerPol")),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="vdp")
    vdp_vr = {v.name: v.valueReference for v in md.modelVariables}
    vdp.instantiate()
    vdp.enterInitializationMode(startTime=0.0, stopTime=stop)
    vdp.exitInitializationMode()
    path = fmu3("CanSignal")
    smd = fmpy.read_model_description(path)
    sig = (path, smd, {v.name: v.valueReference for v in smd.modelVariables})
    bpath = fmu3("CanBus")
    bmd = fmpy.read_model_description(bpath)
    nodes = {n: Node(sig, n, tx_id=d["tx_id"], rx_id=d["rx_id"], period=PERIOD, BusNotifications=True)
             for n, d in NODES.items()}
    bus = Bus((bpath, bmd, {v.name: v.valueReference for v in bmd.modelVariables}), error_every=error_every)
    close = lambda x: 1e-9 * max(abs(x), 1.0)  # noqa: E731
    # Time 0: the Event Mode exitInitializationMode leaves each node in ends; the countdowns read.
    next_tx = {}
    for n, node in nodes.items():
        node.settle()
        h, q = tx_interval(node)
        next_tx[n] = 0.0 + h if q == 2 else None
    bus.settle()
    rows, delivered = [], []

    def record(t):
        x = dict(zip(["vdp.x0", "vdp.x1"], vdp.getFloat64([vdp_vr["x0"], vdp_vr["x1"]])))
        for n, node in nodes.items():
            for v in ("y", "frames_sent", "frames_received", "confirmed", "arbitration_lost", "bus_errors"):
                x[f"{n}.{v}"] = node.get(v)
        x["bus.bus_load"] = bus.get("bus_load")
        for v in ("frames_delivered", "bus_errors", "arbitration_losses"):
            x[f"bus.{v}"] = bus.get(v)
        rows.append((t, x))

    def event(t):
        u = dict(zip(["x0", "x1"], vdp.getFloat64([vdp_vr["x0"], vdp_vr["x1"]])))
        for n, node in nodes.items():
            node.f.setFloat64([node.vr["u"]], [u[NODES[n]["source"]]])
            if next_tx[n] is not None and abs(next_tx[n] - t) <= close(t):
                # The Tx tick: Tx_Data to the port's Rx_Data (the connected Rx_Clock ticks with it).
                tx = node.send(u[NODES[n]["source"]])
                bus.receive(NODES[n]["port"], tx)
                h, q = tx_interval(node)
                next_tx[n] = t + h if q == 2 else None
        if bus.next is not None and abs(bus.next - t) <= close(t):
            out = bus.deliver([1, 2, 3, 4])
            for n, node in nodes.items():
                data = out[NODES[n]["port"]]
                node.receive(data)  # the node's Rx_Clock ticks with its port's Tx_Clock, data or none
                delivered.append((t, NODES[n]["port"], data))
        record(t)

    n_points = round(stop / STEP)
    event(0.0)
    t = 0.0
    for k in range(n_points):
        end = (k + 1) * STEP
        while True:
            ticks = [x for x in list(next_tx.values()) + [bus.next] if x is not None]
            e = min(ticks) if ticks else None
            if e is None or not e < end - close(end):
                break
            vdp.doStep(t, e - t)
            for x in list(nodes.values()) + [bus]:
                x.step(t, e - t)
            t = e
            event(t)
        vdp.doStep(t, end - t)
        for x in list(nodes.values()) + [bus]:
            x.step(t, end - t)
        t = end
        event(t)
    for x in list(nodes.values()):
        x.close()
    vdp.terminate()
    vdp.freeInstance()
    return rows, delivered


@pytest.mark.parametrize("error_every", [0, 3])
def test_a_can_network_in_the_runner_equals_the_fmpy_scheduler_frame_by_frame(error_every, tmp_path):
    stop = 0.1
    got = runner(tmp_path, network_ssp(tmp_path, error_every), stop, STEP, *[a for r in RECORD for a in ("--record", r)])
    rows, delivered = schedule(stop, error_every)
    # The same communication points: the grid and every Tx tick of the nodes and the bus.
    times = np.array([t for t, _ in rows])
    assert len(got["time"]) == len(times), (list(got["time"]), list(times))
    assert np.max(np.abs(np.asarray(got["time"]) - times)) == 0.0
    # Every recorded value after every event, bit for bit.
    for name in RECORD:
        want = np.array([x[name] for _, x in rows], dtype=float)
        assert np.array_equal(np.asarray(got[name]), want), (name, list(got[name]), list(want))
    # Every frame: each CAN Transmit the bus delivered (bytes the scheduler handed on) is in the
    # runner's receiving node at that time (y: the frame's 8 bytes as a double; the count);
    # each Confirm counted by its sender.
    frames = confirms = 0
    index = {t: i for i, t in enumerate(times)}
    for t, port, data in delivered:
        node = next(n for n, d in NODES.items() if d["port"] == port)
        row = index[t]
        for code, args in operations(data):
            if code == 0x10:
                can_id, _, _, payload = transmitted(args)
                if can_id == NODES[node]["rx_id"]:
                    frames += 1
                    assert got[f"{node}.y"][row] == struct.unpack("<d", payload)[0]
            elif code == 0x20:
                confirms += 1
    assert frames == sum(got[f"{n}.frames_received"][-1] for n in NODES) and frames >= 18
    assert confirms == sum(got[f"{n}.confirmed"][-1] for n in NODES)
    if error_every:
        assert got["bus.bus_errors"][-1] >= 3
    print(f"error_every={error_every}: {len(times)} points, {frames} frames, {confirms} confirms compared")


# --- An output clock into a triggered input clock: two of the project's Clocks ---------------

CLOCKS_RECORD = ["a.inClock1Ticks", "a.totalInClockTicks", "a.inClock3Ticks", "b.inClock1Ticks", "b.inClock2Ticks",
                 "b.totalInClockTicks", "b.result2"]


def clocks_schedule(stop, h):
    """Two Clocks instances in fmpy, a's outClock connected to b's inClock2: at each point of the
    grid, an FMU whose time-based clock is due (inClock1 every second, the countdown inClock3
    from the interval read after each event) enters Event Mode and gets it set; a's outClock is
    read with fmi3GetClock after its clocks are set, and where it ticks b's inClock2 is set too
    (b entering Event Mode for it); the clocked outputs are read while their clocks tick; then
    each updates its discrete states, the countdown's interval is read, Step Mode."""
    path = fmu3("Clocks")
    md = fmpy.read_model_description(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmus = {}
    for name in ("a", "b"):
        f = FMU3Slave(guid=md.guid, unzipDirectory=fmpy.extract(path), modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=name)
        f.instantiate(eventModeUsed=True)
        f.enterInitializationMode(startTime=0.0, stopTime=stop)
        f.setInt32([vr["input2"]], [7])
        f.exitInitializationMode()
        fmus[name] = f
    held = {k: 0 for k in CLOCKS_RECORD}
    next3 = {"a": None, "b": None}
    clocked = {"inClock1": ["inClock1Ticks", "totalInClockTicks"], "inClock2": ["inClock2Ticks", "result2"],
               "inClock3": ["totalInClockTicks"]}
    rows = []
    in_event = {"a": True, "b": True}  # exitInitializationMode leaves each in Event Mode
    for k in range(round(stop / h) + 1):
        t = k * h
        if k > 0:
            for name, f in fmus.items():
                f.enterStepMode() if in_event[name] else None
                f.doStep((k - 1) * h, h)
                in_event[name] = False
        out = False
        for name in ("a", "b"):
            f = fmus[name]
            due = []
            if abs(t - round(t)) < 1e-9:
                due.append("inClock1")
            if next3[name] is not None and abs(next3[name] - t) < 1e-9:
                due.append("inClock3")
                next3[name] = None
            if name == "b" and out:
                due.append("inClock2")
            if not due:
                continue
            if not in_event[name]:
                f.enterEventMode()
                in_event[name] = True
            f.setClock([vr[c] for c in due], [True] * len(due))
            if name == "a":
                out = f.getClock([vr["outClock"]])[0]
            for c in due:
                for v in clocked[c]:
                    held[f"{name}.{v}"] = f.getInt32([vr[v]])[0]
        for name, f in fmus.items():
            if in_event[name]:
                while f.updateDiscreteStates()[0]:
                    pass
                intervals, qualifiers = (fmi3Float64 * 1)(), (fmi3IntervalQualifier * 1)()
                f.getIntervalDecimal((fmi3ValueReference * 1)(vr["inClock3"]), intervals, qualifiers)
                if qualifiers[0] == 2:
                    next3[name] = t + intervals[0]
                f.enterStepMode()
                in_event[name] = False
            held[f"{name}.inClock3Ticks"] = f.getInt32([vr["inClock3Ticks"]])[0]  # not clocked
        rows.append((t, dict(held)))
    return rows


def test_an_output_clock_ticks_the_triggered_input_clock_connected_to_it_as_in_fmpy(tmp_path):
    comps = [("a", fmu3("Clocks")), ("b", fmu3("Clocks"))]
    connectors = {"a": [("outClock", "output", "Clock", ())], "b": [("inClock2", "input", "Clock", ())]}
    parameters = {n: [("input2", "Int32", 7, ())] for n in ("a", "b")}
    path, ssd = write_ssp2(tmp_path / "Clocks.ssp", comps, connectors, [("a", "outClock", "b", "inClock2")], parameters)
    valid(ssd)
    stop, h = 10.0, 0.5
    got = runner(tmp_path, path, stop, h, *[a for r in CLOCKS_RECORD for a in ("--record", r)])
    rows = clocks_schedule(stop, h)
    assert list(got["time"]) == [t for t, _ in rows]
    for name in CLOCKS_RECORD:
        want = [x[name] for _, x in rows]
        assert list(got[name]) == want, (name, list(got[name]), want)
    # a's fifth input tick (t = 4) and tenth tick the clock connection passed on to b.
    assert got["b.inClock2Ticks"][-1] >= 2 and got["b.result2"][-1] == 7


# --- Early return: a component's event ends every component's step ---------------------------

def early_schedule(stop, h):
    """The project's BouncingBall (FMI 3.0) with eventModeUsed and earlyReturnAllowed beside a
    VanDerPol, in fmpy: the ball steps first; where it returns early (its bounce), the oscillator
    steps to that time, the ball's Event Mode is handled (updates until none is needed) and the
    point is recorded; then on to the grid point."""
    def load(name, **kw):
        path = fmu3(name)
        md = fmpy.read_model_description(path)
        f = FMU3Slave(guid=md.guid, unzipDirectory=fmpy.extract(path), modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=name)
        f.instantiate(**kw)
        f.enterInitializationMode(startTime=0.0, stopTime=stop)
        f.exitInitializationMode()
        return f, {v.name: v.valueReference for v in md.modelVariables}
    ball, bvr = load("BouncingBall", eventModeUsed=True, earlyReturnAllowed=True)
    vdp, vvr = load("VanDerPol")

    def event():
        while ball.updateDiscreteStates()[0]:
            pass
        ball.enterStepMode()

    def record(t):
        rows.append((t, dict(zip(["ball.h", "ball.v"], ball.getFloat64([bvr["h"], bvr["v"]])),
                             **{"vdp.x0": vdp.getFloat64([vvr["x0"]])[0]})))
    rows = []
    event()
    record(0.0)
    t = 0.0
    for k in range(round(stop / h)):
        end = (k + 1) * h
        while True:
            need, terminate, early, last = ball.doStep(t, end - t)
            assert not terminate
            reached = last if early and last < end else end
            vdp.doStep(t, reached - t)
            t = reached
            if need:
                ball.enterEventMode()
                event()
            record(t)
            if reached == end:
                break
    return rows


def test_an_early_return_ends_every_components_step_at_the_event_as_in_fmpy(tmp_path):
    comps = [("ball", fmu3("BouncingBall")), ("vdp", fmu3("VanDerPol"))]
    path, ssd = write_ssp2(tmp_path / "Early.ssp", comps, {}, [], {})
    stop, h = 3.0, 0.1
    record = ["ball.h", "ball.v", "vdp.x0"]
    got = runner(tmp_path, path, stop, h, "--event-mode", "ball", *[a for r in record for a in ("--record", r)])
    rows = early_schedule(stop, h)
    assert list(got["time"]) == [t for t, _ in rows]
    for name in record:
        assert list(got[name]) == [x[name] for _, x in rows], name
    # The points off the grid are the bounces: the first two at the free fall's exact times
    # (h0 = 1 m, g = 9.81 m/s^2, e = 0.7), and the ball leaves each going up.
    grid = {round(k * h, 9) for k in range(round(stop / h) + 1)}
    bounces = [i for i, t in enumerate(got["time"]) if round(t, 9) not in grid]
    t1 = math.sqrt(2 / 9.81)
    t2 = t1 + 2 * 0.7 * 9.81 * t1 / 9.81
    assert len(bounces) >= 4
    assert abs(got["time"][bounces[0]] - t1) < 1e-9 and abs(got["time"][bounces[1]] - t2) < 1e-9
    assert all(got["ball.v"][i] > 0 for i in bounces[:4])
    # Without event mode the ball is stepped over its bounces on the grid alone.
    plain = runner(tmp_path, path, stop, h, "--record", "ball.h")
    assert len(plain["time"]) == round(stop / h) + 1


def test_the_python_module_runs_event_mode_components_as_the_command_line(tmp_path):
    """System(path, event_mode=[...]) is the command line's --event-mode: the BouncingBall beside
    the VanDerPol, the same points (the grid and every bounce) and values, bit for bit, also with
    isolate (each component or the whole system in a child process); refused for a name that is
    no component."""
    import rustfmu_runner

    comps = [("ball", fmu3("BouncingBall")), ("vdp", fmu3("VanDerPol"))]
    path, ssd = write_ssp2(tmp_path / "Early.ssp", comps, {}, [], {})
    stop, h = 3.0, 0.1
    record = ["ball.h", "ball.v", "vdp.x0"]
    got = runner(tmp_path, path, stop, h, "--event-mode", "ball", *[a for r in record for a in ("--record", r)])
    r = rustfmu_runner.System(path, event_mode=["ball"]).run(stop, h, record=record)
    assert len(r["time"]) > round(stop / h) + 1, "no bounce became a point"
    assert np.array_equal(r["time"], got["time"])
    for name in record:
        assert np.array_equal(r[name], got[name]), name
    plain = rustfmu_runner.System(path).run(stop, h, record=record)
    assert len(plain["time"]) == round(stop / h) + 1
    for isolate in ("component", "system"):
        iso = rustfmu_runner.System(path, isolate=isolate, event_mode=["ball"]).run(stop, h, record=record)
        assert np.array_equal(iso["time"], got["time"]), isolate
        for name in record:
            assert np.array_equal(iso[name], got[name]), (isolate, name)
    with pytest.raises(rustfmu_runner.VariableError, match="nope"):
        rustfmu_runner.System(path, event_mode=["nope"])


def two_balls_schedule(stop, h, h0):
    """Two of the project's BouncingBalls (FMI 3.0) with eventModeUsed and earlyReturnAllowed,
    in fmpy, `a` stepped first, `b` dropped from `h0[1]`: at each step both FMU states are kept;
    where one returns early before the time the other reached, that one is set back
    (fmi3SetFMUState) and steps again to the earlier time, until both stop at one time; the
    Event Modes are handled and the point recorded; then on to the grid point. Returns the rows
    and how many steps were taken back."""
    balls, vrs = [], None
    for name, height in zip("ab", h0):
        path = fmu3("BouncingBall")
        md = fmpy.read_model_description(path)
        f = FMU3Slave(guid=md.guid, unzipDirectory=fmpy.extract(path),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        f.instantiate(eventModeUsed=True, earlyReturnAllowed=True)
        vrs = {v.name: v.valueReference for v in md.modelVariables}
        f.setFloat64([vrs["h"]], [height])
        f.enterInitializationMode(startTime=0.0, stopTime=stop)
        f.exitInitializationMode()
        balls.append(f)

    def event(f):
        while f.updateDiscreteStates()[0]:
            pass
        f.enterStepMode()

    def record(t):
        values = {}
        for name, f in zip("ab", balls):
            values[f"{name}.h"], values[f"{name}.v"] = f.getFloat64([vrs["h"], vrs["v"]])
        rows.append((t, values))
    rows, rolled = [], 0
    for f in balls:
        event(f)
    record(0.0)
    t = 0.0
    for k in range(round(stop / h)):
        end = (k + 1) * h
        while True:
            states = [f.getFMUState() for f in balls]
            target, reached, need = end, [None, None], [False, False]
            moved = True
            while moved:
                moved = False
                for i, f in enumerate(balls):
                    if reached[i] == target:
                        continue
                    if reached[i] is not None:
                        f.setFMUState(states[i])
                        rolled += 1
                    need[i], terminate, early, last = f.doStep(t, target - t, noSetFMUStatePriorToCurrentPoint=False)
                    assert not terminate
                    if early and last < target:
                        target, moved = last, True
                    reached[i] = target
            for f, s in zip(balls, states):
                f.freeFMUState(s)
            t = target
            for i, f in enumerate(balls):
                if need[i]:
                    f.enterEventMode()
                    event(f)
            record(t)
            if t == end:
                break
    return rows, rolled


def test_two_early_returns_in_one_step_take_the_later_one_back_as_in_fmpy(tmp_path):
    """Two BouncingBalls with --event-mode, `a` (dropped from 1 m) stepped first, `b` from 0.9 m:
    in the step from 0.4 s `a` returns early at its bounce (0.4515 s), then `b` at its own, earlier
    (0.4284 s); `a` is set back to its state at 0.4 s (fmi3SetFMUState) and steps again to 0.4284 s.
    The same points and values as fmpy with the test's scheduler that does the same, bit for bit,
    every bounce of each ball a point of its own at the free fall's exact time (within 1e-9 s)."""
    comps = [("a", fmu3("BouncingBall")), ("b", fmu3("BouncingBall"))]
    path, ssd = write_ssp2(tmp_path / "Balls.ssp", comps, {}, [], {})
    stop, h = 1.5, 0.1
    record = ["a.h", "a.v", "b.h", "b.v"]
    got = runner(tmp_path, path, stop, h, "--event-mode", "a", "--event-mode", "b", "--set", "b.h=0.9",
                 *[a for r in record for a in ("--record", r)])
    rows, rolled = two_balls_schedule(stop, h, (1.0, 0.9))
    assert rolled > 0, "the scheduler never set a ball back: the case is not tested"
    assert list(got["time"]) == [t for t, _ in rows]
    for name in record:
        assert list(got[name]) == [x[name] for _, x in rows], name
    # Each ball's first two bounces are points, at the free fall's times (g = 9.81 m/s^2, e = 0.7).
    for h0 in (1.0, 0.9):
        t1 = math.sqrt(2 * h0 / 9.81)
        t2 = t1 + 2 * 0.7 * t1
        for tb in (t1, t2):
            assert np.min(np.abs(got["time"] - tb)) < 1e-9, (h0, tb)
    # Both first bounces fall in the step from 0.4 s, b's first although a steps first.
    assert 0.4 < math.sqrt(1.8 / 9.81) < math.sqrt(2 / 9.81) < 0.5


# --- Triggered output Tx clocks: two CanSignalTriggered nodes connected directly ------------

def test_triggered_output_tx_clocks_carry_frames_both_ways_as_the_fmpy_scheduler_of_test_ls_bus_triggered(tmp_path):
    """Each node's Tx_Clock is a triggered output clock ticking at its own time events (the step
    that reaches one ends with eventHandlingNeeded; fmi3GetClock says it ticks): the runner
    connects it to the other node's Rx_Clock (FMI-LS-BUS 1.0.0, Triggered Tx Clocks), Tx_Data to
    Rx_Data. Where both send at once (every 20 ms) the second frame is taken in a second round of
    the same Event Mode. Against test_ls_bus_triggered's own fmpy scheduler (t += h): every send
    at the same time (to the ulps t += h adds), every frame's signal received."""
    import test_ls_bus_triggered as trig
    path = fmu3("CanSignalTriggered")
    params = {"sensor": dict(tx_id=0x123, rx_id=0x200, period=0.01, u=2.5),
              "actuator": dict(tx_id=0x200, rx_id=0x123, period=0.02, u=-1.25)}
    connectors = {n: [("CAN.Tx_Clock", "output", "Clock", ()), ("CAN.Tx_Data", "output", "Binary", ()),
                      ("CAN.Rx_Clock", "input", "Clock", ()), ("CAN.Rx_Data", "input", "Binary", ())] for n in params}
    links = []
    for a, b in (("sensor", "actuator"), ("actuator", "sensor")):
        links += [(a, "CAN.Tx_Clock", b, "CAN.Rx_Clock"), (a, "CAN.Tx_Data", b, "CAN.Rx_Data")]
    ssv = {"Int32": "Int32", "Float64": "Float64"}
    parameters = {n: [(k, ssv["Int32" if isinstance(v, int) else "Float64"], v, ()) for k, v in p.items()]
                  for n, p in params.items()}
    ssp, ssd = write_ssp2(tmp_path / "Triggered.ssp", [(n, path) for n in params], connectors, links, parameters)
    valid(ssd)
    record = [f"{n}.{v}" for n in params for v in ("y", "frames_sent", "frames_received")]
    stop = 0.1
    got = runner(tmp_path, ssp, stop, trig.H, *[a for r in record for a in ("--record", r)])
    md = fmpy.read_model_description(path)
    fmu = (path, md, {v.name: v.valueReference for v in md.modelVariables})
    nodes = {n: trig.Node(fmu, n, **p) for n, p in params.items()}
    sent = trig.run(list(nodes.values()), stop=stop)
    time = np.asarray(got["time"])
    frames = 0
    for name, node in nodes.items():
        other = next(n for n in nodes if n != name)
        want = [t for t, n, _ in sent if n is node]
        counts = np.asarray(got[f"{name}.frames_sent"])
        at = time[1:][np.diff(counts) > 0]
        assert len(at) == len(want) and np.max(np.abs(at - np.array(want))) < 1e-12, (name, list(at), want)
        # Every frame it sent arrived at the other node at that point, its signal bit for bit.
        received = np.asarray(got[f"{other}.frames_received"])
        assert list(time[1:][np.diff(received) > 0]) == list(at)
        for t, n, data in sent:
            if n is node:
                [(can_id, payload)] = trig.frames(data)
                assert can_id == params[name]["tx_id"]
                i = int(np.argmin(np.abs(time - t)))
                assert got[f"{other}.y"][i] == struct.unpack("<d", payload)[0] == params[name]["u"]
                frames += 1
        assert got[f"{name}.frames_sent"][-1] == node.get("frames_sent")
        assert got[f"{other}.frames_received"][-1] == nodes[other].get("frames_received")
    assert frames == 15
    print(f"triggered: {frames} frames compared")
