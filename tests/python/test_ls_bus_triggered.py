"""FMI-LS-BUS 1.0.0 network FMUs with a *triggered output* Tx clock (CanSignalTriggered,
holonomic/fmus/can_signal_triggered), run by a scheduler of this test that keeps time the way FMU
Compliance Checker and FMU Manipulation Toolbox's containers do: t += h.

A node with a triggered Tx_Clock sends at its own time events: the step that reaches one ends with
eventHandlingNeeded, and in the importer's Event Mode fmi3GetClock says the clock ticks and
Tx_Data holds the frame ("a triggered Tx_Clock must only be set when returning from fmi3DoStep
with the earlyReturn argument set to fmi3False", FMI-LS-BUS 1.0.0, Triggered Tx Clocks). With
t += h the 10th step of 0.001 ends at 0.010000000000000002, two ulps past the send time 0.01: the
event is the communication point's all the same. (Before, the runtime handled it inside the step,
and the tick was over before the importer could ask: the frame never left the node.)

Every operation is read with `struct` from the standard's tables (OP code, Length, arguments,
little-endian), independently of the Rust codec the FMU uses."""

import struct

import pytest

from fmi_harness import EventModeSlave, fmu3_with_vrs

H = 0.001
PERIOD = 0.01


@pytest.fixture(scope="module")
def triggered():
    return fmu3_with_vrs("CanSignalTriggered")


def frames(buffer):
    """The CAN Transmit operations (OP 0x10) of a Tx/Rx_Data value: [(ID, data)]; every
    operation's Length must delimit it."""
    out, at = [], 0
    while at < len(buffer):
        code, length = struct.unpack_from("<II", buffer, at)
        assert 8 <= length <= len(buffer) - at, buffer.hex()
        if code == 0x10:
            can_id, _ide, _rtr, n = struct.unpack_from("<IBBH", buffer, at + 8)
            assert length == 16 + n
            out.append((can_id, buffer[at + 16:at + 16 + n]))
        at += length
    return out


class Node(EventModeSlave):
    """One CanSignalTriggered instance in co-simulation with event mode, in Step Mode after
    __init__."""

    def __init__(self, fmu, name, **params):
        super().__init__(fmu, name, **params)
        self.settle()
        self.f.enterStepMode()

    def get(self, name, kind="Int32"):
        return getattr(self.f, f"get{kind}")([self.vr[name]])[0]


def run(nodes, stop, h=H):
    """The scheduler: every node steps by h from t (t += h); where one asks for Event Mode, all
    enter it, each node's Tx_Clock is asked and the tick ends, then what a ticking node sent is
    handed to every other node as Rx_Data with its Rx_Clock activated, one receiver and one
    frame at a time. Returns [(t, sender, Tx_Data)]."""
    sent, t = [], 0.0
    while t < stop - h / 2:
        events = []
        for n in nodes:
            event, terminate, early, _ = n.f.doStep(t, h)
            assert not terminate and not early
            events.append(event)
        t += h
        if not any(events):
            continue
        for n in nodes:
            n.f.enterEventMode()
        ticks = []
        for n in nodes:
            if n.f.getClock([n.vr["CAN.Tx_Clock"]])[0]:
                ticks.append((n, n.f.getBinary([n.vr["CAN.Tx_Data"]])[0]))
        # The tick that read the Tx clocks ends first: a node that both sends and receives at
        # this time has evaluated its tick (fmi3GetClock) and takes no input for it any more.
        for n in nodes:
            n.settle()
        # Then the frames are delivered in a second round of the same Event Mode.
        for sender, data in ticks:
            sent.append((t, sender, data))
            for n in nodes:
                if n is not sender:
                    n.f.setClock([n.vr["CAN.Rx_Clock"]], [True])
                    n.f.setBinary([n.vr["CAN.Rx_Data"]], [data])
                    n.settle()
        for n in nodes:
            n.f.enterStepMode()
    return sent


def test_a_triggered_tx_clock_ticks_at_each_send_time_of_an_importer_keeping_time_as_t_plus_h(triggered):
    sensor = Node(triggered, "sensor", tx_id=0x123, rx_id=0x7FF, period=PERIOD, u=2.5)
    actuator = Node(triggered, "actuator", tx_id=0x200, rx_id=0x123, period=0.02)
    sent = run([sensor, actuator], stop=0.1)

    by_sensor = [(t, data) for t, n, data in sent if n is sensor]
    # Once per period, at the communication point that reaches it (t += h: 0.010000000000000002,
    # 0.02000000000000001, ...): not lost, not twice.
    assert len(by_sensor) == 10, [t for t, _ in by_sensor]
    for k, (t, data) in enumerate(by_sensor, start=1):
        assert abs(t - k * PERIOD) < 1e-12, (k, t)
        assert frames(data) == [(0x123, struct.pack("<d", 2.5))], data.hex()
    assert len([1 for _, n, _ in sent if n is actuator]) == 5
    assert sensor.get("frames_sent") == 10
    # The actuator took the sensor's signal from frame 0x123; the sensor ignored frame 0x200.
    assert actuator.get("y", "Float64") == 2.5
    assert actuator.get("frames_received") == 10
    assert sensor.get("frames_received") == 0
    assert sensor.get("y", "Float64") == 0.0


def test_between_send_times_the_tx_clock_does_not_tick_and_tx_data_is_empty(triggered):
    node = Node(triggered, "node", tx_id=0x100, period=PERIOD)
    t = 0.0
    for k in range(1, 15):
        event = node.f.doStep(t, H)[0]
        t += H
        # The step asks for Event Mode where the send time is reached, and only there.
        assert event == (k == 10), (k, t)
        node.f.enterEventMode()
        ticks = node.f.getClock([node.vr["CAN.Tx_Clock"]])[0]
        assert ticks == (k == 10), (k, t)
        if ticks:
            assert len(frames(node.f.getBinary([node.vr["CAN.Tx_Data"]])[0])) == 1
        node.settle()
        node.f.enterStepMode()
    assert node.get("frames_sent") == 1


def test_a_send_time_inside_a_step_ticks_the_tx_clock_at_the_steps_end(triggered):
    """An importer whose grid moved (FMU Manipulation Toolbox's container shortens a step to a
    bus simulation's countdown tick, then steps by h from there): the send times 0.01, 0.02, ...
    fall strictly inside steps. Each is signalled at the end of the step that holds it (FMI-LS-BUS
    1.0.0, Triggered Tx Clocks: "Pending Tx data shall be signaled by returning from fmi3DoStep
    with the eventHandlingNeeded arguments set to fmi3True"), the next one still a period after
    the send time (no drift with the grid)."""
    node = Node(triggered, "node", tx_id=0x100, period=PERIOD, u=1.5)
    t, ticks = 0.0, []
    for dt in [0.0004] + [H] * 40:
        event = node.f.doStep(t, dt)[0]
        t += dt
        node.f.enterEventMode()
        ticked = node.f.getClock([node.vr["CAN.Tx_Clock"]])[0]
        assert ticked == event, t
        if ticked:
            ticks.append((t, frames(node.f.getBinary([node.vr["CAN.Tx_Data"]])[0])))
        node.settle()
        node.f.enterStepMode()
    assert [round(t, 9) for t, _ in ticks] == [0.0104, 0.0204, 0.0304, 0.0404]
    assert all(f == [(0x100, struct.pack("<d", 1.5))] for _, f in ticks)
    assert node.get("frames_sent") == 4
