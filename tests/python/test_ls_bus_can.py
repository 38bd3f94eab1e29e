"""FMI-LS-BUS 1.0.0 (CAN, Low Cut) as fmpy drives it: the CanSignal network FMU (holonomic/fmus/
can_signal, declared with `#[fmu(can_network(..))]`) run by a scheduler of this test, the way the
layered standard describes an importer: at each bus communication point, in Event Mode, the
sender's Tx_Clock is activated and its Tx_Data read; the bytes are handed to the receivers as
Rx_Data with their Rx_Clock activated (direct communication, no bus simulation).

Every bus operation is read and written here with `struct`, from the standard's tables (OP code,
Length, arguments, little-endian): independent of the Rust codec the FMU uses (whose bytes
ls-bus/tests/c_headers.rs compares with the standard's C header macros). The packaging is checked
against the standard's schemas: terminalsAndIcons.xml against FMI 3.0's, the manifest against
FMI-LS-BUS's (`../shared/independent/`)."""

import math
import pathlib
import struct
import subprocess
import sys
import zipfile

import fmpy
import pytest
from fmpy.fmi3 import fmi3Float64, fmi3IntervalQualifier, fmi3ValueReference
from lxml import etree

from conftest import FMU_DIR, ROOT
from fmi_harness import EventModeSlave, fmu3_with_vrs

sys.path.insert(0, str(ROOT / "examples"))
# A frame's bits from ISO 11898-1, written in Python (not taken from the Rust code).
from ls_bus_loop import can_bits  # noqa: E402

INDEPENDENT = ROOT.parent / "shared" / "independent"
CARGO_FMU = FMU_DIR.parent / "release" / "cargo-fmu"
MIME = 'application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0"'
PERIOD = 0.01


def op(code, args=b""):
    """One bus operation: OP Code, Length (of the whole operation), arguments (FMI-LS-BUS 1.0.0)."""
    return struct.pack("<II", code, 8 + len(args)) + args


def can_transmit(can_id, data, ide=0, rtr=0):
    """CAN Transmit (0x10): ID, Ide, Rtr, Data Length, Data; Length = 16 + Data Length."""
    return op(0x10, struct.pack("<IBBH", can_id, ide, rtr, len(data)) + data)


def operations(buffer):
    """The operations of a Tx/Rx_Data value: [(op code, arguments)]; each Length must delimit one."""
    out, at = [], 0
    while at < len(buffer):
        code, length = struct.unpack_from("<II", buffer, at)
        assert 8 <= length <= len(buffer) - at, (at, length, buffer.hex())
        out.append((code, buffer[at + 8:at + length]))
        at += length
    return out


def transmitted(args):
    """CAN Transmit's arguments: (ID, Ide, Rtr, Data)."""
    can_id, ide, rtr, n = struct.unpack_from("<IBBH", args)
    assert len(args) == 8 + n
    return can_id, ide, rtr, args[8:]


@pytest.fixture(scope="module")
def can_signal():
    return fmu3_with_vrs("CanSignal")


class Node(EventModeSlave):
    """One CanSignal instance in co-simulation with event mode, its messages kept; after __init__
    in Event Mode."""

    def send(self, u):
        """A Tx tick: u set, Tx_Clock activated; the Tx_Data it gives."""
        self.f.setClock([self.vr["CAN.Tx_Clock"]], [True])
        self.f.setFloat64([self.vr["u"]], [u])
        # A clocked output is read while its clock is active, before the update ends the tick.
        tx = self.f.getBinary([self.vr["CAN.Tx_Data"]])[0]
        self.settle()
        return tx

    def receive(self, data):
        """An Rx tick: Rx_Data set, Rx_Clock activated."""
        self.f.setClock([self.vr["CAN.Rx_Clock"]], [True])
        self.f.setBinary([self.vr["CAN.Rx_Data"]], [data])
        self.settle()

    def get(self, name):
        v = self.vr[name]
        return self.f.getFloat64([v])[0] if name == "y" else self.f.getInt32([v])[0]

    def step(self, t, h):
        self.f.enterStepMode()
        event, terminate, early, _ = self.f.doStep(t, h)
        assert not terminate and not early
        self.f.enterEventMode()

    def close(self):
        self.f.terminate()
        self.f.freeInstance()


def test_two_nodes_connected_directly_carry_the_signal_frame_by_frame(can_signal):
    sensor = Node(can_signal, "sensor", tx_id=0x123, rx_id=0x7FF, period=PERIOD)
    actuator = Node(can_signal, "actuator", tx_id=0x200, rx_id=0x123, period=PERIOD)
    intervals, qualifiers = (fmi3Float64 * 1)(), (fmi3IntervalQualifier * 1)()
    sensor.f.getIntervalDecimal((fmi3ValueReference * 1)(sensor.vr["CAN.Tx_Clock"]), intervals, qualifiers)
    # A countdown clock: the importer schedules the first Tx tick one interval on.
    assert intervals[0] == PERIOD and qualifiers[0] == 2  # fmi3IntervalChanged
    n = 20
    for k in range(1, n + 1):
        sensor.step((k - 1) * PERIOD, PERIOD)
        actuator.step((k - 1) * PERIOD, PERIOD)
        t = k * PERIOD
        u = math.sin(2 * math.pi * t) + 0.25
        tx = sensor.send(u)
        [(code, args)] = operations(tx)
        assert code == 0x10 and len(tx) == 16 + 8
        assert transmitted(args) == (0x123, 0, 0, struct.pack("<d", u))
        actuator.send(0.0)  # its own tick, ignored by the sensor here
        actuator.receive(tx)
        assert actuator.get("y") == u
    assert sensor.get("frames_sent") == n
    assert actuator.get("frames_received") == n
    assert actuator.get("format_errors") == 0
    sensor.close()
    actuator.close()


def test_a_malformed_buffer_is_applied_not_at_all_logged_and_answered_with_a_format_error(can_signal):
    node = Node(can_signal, "node", tx_id=0x100, rx_id=0x123)
    bad = op(0x41, b"\x09")  # Status with a status kind the standard does not define
    node.receive(can_transmit(0x123, struct.pack("<d", 1.5)) + bad)
    assert node.get("y") == 0.0 and node.get("frames_received") == 0, "a frame of the refused buffer was applied"
    assert node.get("format_errors") == 1
    refusal = [m for m in node.messages if "CAN.Rx_Data refused" in m]
    assert refusal and "byte 24" in refusal[0] and "Status: 0x09" in refusal[0], node.messages
    # The reply at the next Tx tick: Format Error (0x01, Length = 10 + Data Length, the whole
    # offending operation as its data), then the node's own frame.
    tx = node.send(2.0)
    (c1, a1), (c2, a2) = operations(tx)
    assert c1 == 0x01 and struct.unpack_from("<H", a1)[0] == len(bad) and a1[2:] == bad
    assert c2 == 0x10 and transmitted(a2) == (0x100, 0, 0, struct.pack("<d", 2.0))
    # ... and the next good buffer is applied again; Tx_Data was emptied after being read.
    node.step(0.0, PERIOD)
    node.receive(can_transmit(0x123, struct.pack("<d", -3.0)))
    assert node.get("y") == -3.0 and node.get("frames_received") == 1
    [(c, _)] = operations(node.send(0.5))
    assert c == 0x10
    node.close()


def test_bus_notifications_for_its_frames_are_counted_and_others_ignored(can_signal):
    node = Node(can_signal, "node", tx_id=0x100, rx_id=0x123, BusNotifications=True)
    confirm = op(0x20, struct.pack("<I", 0x100))
    confirm_other = op(0x20, struct.pack("<I", 0x555))
    lost = op(0x30, struct.pack("<I", 0x100))
    bus_error = op(0x31, struct.pack("<IBBB", 0x100, 0x04, 0x01, 1))  # CRC error, primary, sender
    wrong_id = can_transmit(0x124, struct.pack("<d", 9.0))
    fd = op(0x11, struct.pack("<IBBBH", 0x123, 0, 1, 0, 8) + struct.pack("<d", 7.0))  # CAN FD: not this node's format
    node.receive(confirm + confirm_other + lost + bus_error + wrong_id + fd)
    assert [node.get(n) for n in ("confirmed", "arbitration_lost", "bus_errors", "frames_received", "format_errors")] \
        == [1, 1, 1, 0, 0]
    assert node.get("y") == 0.0
    node.close()


def test_a_truncated_or_lying_buffer_changes_nothing(can_signal):
    node = Node(can_signal, "node", tx_id=0x100, rx_id=0x123)
    good = can_transmit(0x123, struct.pack("<d", 4.0))
    for broken in (good[:-1],  # Length says more than the buffer has
                   good + b"\x10\x00",  # a header cut short
                   op(0x10, struct.pack("<IBBH", 0x123, 0, 0, 9) + bytes(9)),  # 9 bytes in classic CAN
                   op(0x10, struct.pack("<IBBH", 0x800, 0, 0, 8) + bytes(8)),  # an 11-bit ID of 12 bits
                   op(0x99)):  # no such OP code
        node.receive(broken)
        assert node.get("y") == 0.0 and node.get("frames_received") == 0, broken.hex()
    assert node.get("format_errors") == 5
    node.close()


def test_the_package_is_what_fmi_ls_bus_prescribes(can_signal):
    path, md, _ = can_signal
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        terminals = z.read("terminalsAndIcons/terminalsAndIcons.xml")
        manifest = z.read("extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml")
    assert {"terminalsAndIcons/terminalsAndIcons.xml", "extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml"} <= names
    # terminalsAndIcons.xml against FMI 3.0's schema (fmpy ships it).
    schema_dir = pathlib.Path(fmpy.__file__).parent / "schema" / "fmi3"
    schema = etree.XMLSchema(etree.parse(str(schema_dir / "fmi3TerminalsAndIcons.xsd")))
    doc = etree.fromstring(terminals)
    assert schema.validate(doc), schema.error_log
    [bus] = doc.findall("Terminals/Terminal")
    assert (bus.get("terminalKind"), bus.get("matchingRule")) == ("org.fmi-ls-bus.network-terminal",
                                                                   "org.fmi-ls-bus.transceiver")
    assert sorted(m.get("memberName") for m in bus.findall("TerminalMemberVariable")) == \
        ["Rx_Clock", "Rx_Data", "Tx_Clock", "Tx_Data"]
    assert {m.get("variableKind") for m in bus.findall("TerminalMemberVariable")} == {"signal"}
    [config] = bus.findall("Terminal")
    assert (config.get("name"), config.get("terminalKind"), config.get("matchingRule")) == \
        ("Configuration", "org.fmi-ls-bus.network-terminal.configuration", "bus")
    assert [m.get("memberName") for m in config.findall("TerminalMemberVariable")] == ["BusNotifications"]
    # The manifest against FMI-LS-BUS's schema, whose import of FMI 3.0's manifest schema (a URL)
    # is pointed at the local copy.
    xsd = etree.parse(str(INDEPENDENT / "fmi-ls-bus-1.0.0/schema/fmi3LayeredStandardBusManifest.xsd"))
    for imp in xsd.getroot().findall("{http://www.w3.org/2001/XMLSchema}import"):
        imp.set("schemaLocation", str(INDEPENDENT / "fmi-standard/3.0.2/schema/fmi3LayeredStandardManifest.xsd"))
    bus_schema = etree.XMLSchema(xsd)
    assert bus_schema.validate(etree.fromstring(manifest)), bus_schema.error_log
    # The data variables: Binary, the CAN MIME type, clocked by their clocks; the clocks' kinds.
    v = {x.name: x for x in md.modelVariables}
    assert v["CAN.Rx_Data"].type == v["CAN.Tx_Data"].type == "Binary"
    with zipfile.ZipFile(path) as z:
        xml = etree.fromstring(z.read("modelDescription.xml"))
    mime = {b.get("name"): b.get("mimeType") for b in xml.iter("Binary")}
    assert mime == {"CAN.Rx_Data": MIME, "CAN.Tx_Data": MIME}
    assert (v["CAN.Rx_Data"].causality, v["CAN.Tx_Data"].causality) == ("input", "output")
    assert v["CAN.Rx_Data"].clocks == [v["CAN.Rx_Clock"]] and v["CAN.Tx_Data"].clocks == [v["CAN.Tx_Clock"]]
    assert v["CAN.Rx_Clock"].intervalVariability == "triggered"
    assert fmpy.validation.validate_fmu(path) == []


def test_cargo_fmu_validate_names_the_rule_a_broken_package_breaks(can_signal, tmp_path):
    path, _, _ = can_signal
    ok = subprocess.run([CARGO_FMU, "fmu", "validate", path], capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr

    def broken(name, change):
        out = tmp_path / name
        with zipfile.ZipFile(path) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
            for item in src.infolist():
                data = change(item.filename, src.read(item.filename))
                if data is not None:
                    dst.writestr(item, data)
        return subprocess.run([CARGO_FMU, "fmu", "validate", out], capture_output=True, text=True)

    no_manifest = broken("no-manifest.fmu", lambda n, d: None if n.endswith("fmi-ls-manifest.xml") else d)
    assert no_manifest.returncode != 0
    assert "requires the use of a layered standard manifest file" in no_manifest.stderr, no_manifest.stderr
    plug = broken("plug.fmu", lambda n, d: d.replace(b'matchingRule="org.fmi-ls-bus.transceiver"', b'matchingRule="plug"')
                  if n.startswith("terminalsAndIcons") else d)
    assert plug.returncode != 0
    assert "must be org.fmi-ls-bus.transceiver" in plug.stderr, plug.stderr


def test_cargo_fmu_check_passes_on_the_network_fmu(can_signal):
    path, _, _ = can_signal
    out = subprocess.run([CARGO_FMU, "fmu", "check", "--strict", path], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-2000:]
    assert " 0 failed, 0 warned" in out.stdout, out.stdout[-2000:]


# --- The bus simulation: CanBus between network FMUs ------------------------------------------

@pytest.fixture(scope="module")
def can_bus():
    return fmu3_with_vrs("CanBus")


class Bus(EventModeSlave):
    """The CanBus instance: ports 1..4, the countdown Tx clocks read after every event."""

    def __init__(self, fmu, **params):
        self.t = 0.0
        self.next = None
        super().__init__(fmu, "bus", **params)

    def settle(self):
        super().settle()
        # A countdown clock whose interval changed: the importer schedules its tick.
        vrs = (fmi3ValueReference * 1)(self.vr["Node1.Tx_Clock"])
        intervals, qualifiers = (fmi3Float64 * 1)(), (fmi3IntervalQualifier * 1)()
        self.f.getIntervalDecimal(vrs, intervals, qualifiers)
        if qualifiers[0] == 2:  # fmi3IntervalChanged
            self.next = self.t + intervals[0]

    def receive(self, port, data):
        self.f.setClock([self.vr[f"Node{port}.Rx_Clock"]], [True])
        self.f.setBinary([self.vr[f"Node{port}.Rx_Data"]], [data])
        self.settle()

    def deliver(self, ports):
        """The bus's Tx tick: what each port gets."""
        self.f.setClock([self.vr[f"Node{p}.Tx_Clock"] for p in ports], [True] * len(ports))
        out = {p: self.f.getBinary([self.vr[f"Node{p}.Tx_Data"]])[0] for p in ports}
        self.next = None
        self.settle()
        return out

    def step(self, t, h):
        self.f.enterStepMode()
        event, terminate, early, _ = self.f.doStep(t, h)
        assert not terminate and not early
        self.f.enterEventMode()
        self.t = t + h

    def get(self, name):
        v = self.vr[name]
        return self.f.getFloat64([v])[0] if name == "bus_load" else self.f.getInt32([v])[0]


def run_network(nodes, bus, stop, inputs):
    """The scheduler of an importer with a bus simulation: nodes[i] is on port i + 1; at each
    time point, every node whose Tx clock ticks sends (its Tx_Data into its port's Rx_Data), then
    the bus delivers if its countdown ended (each port's Tx_Data into its node's Rx_Data). The
    next time point is the earliest of the nodes' Tx ticks and the bus's countdown. Returns the
    deliveries: [(time, port, operations)]."""
    deliveries, t = [], 0.0
    next_tx = [node.period for node in nodes]  # countdown clocks: the first tick one period on
    while t <= stop + 1e-12:
        for i, node in enumerate(nodes):
            if abs(next_tx[i] - t) < 1e-12:
                tx = node.send(inputs[i](t))
                if tx:
                    bus.receive(i + 1, tx)
                next_tx[i] += node.period
        if bus.next is not None and abs(bus.next - t) < 1e-12:
            for port, data in bus.deliver([1, 2, 3, 4]).items():
                if data and port <= len(nodes):
                    nodes[port - 1].receive(data)
                    deliveries.append((t, port, operations(data)))
        candidates = next_tx + ([bus.next] if bus.next is not None else [])
        t_next = min(candidates)
        if t_next > stop + 1e-12:
            break
        for node in nodes:
            node.step(t, t_next - t)
        bus.step(t, t_next - t)
        t = t_next
    return deliveries


def test_a_frame_crosses_the_bus_in_its_bit_time_and_is_confirmed(can_signal, can_bus):
    sensor = Node(can_signal, "sensor", tx_id=0x123, rx_id=0x7FF, period=PERIOD, BusNotifications=True)
    actuator = Node(can_signal, "actuator", tx_id=0x200, rx_id=0x123, period=PERIOD, BusNotifications=True)
    sensor.period = actuator.period = PERIOD
    bus = Bus(can_bus)
    u = [lambda t: math.cos(t) + 0.5, lambda t: 0.0]
    deliveries = run_network([sensor, actuator], bus, 0.055, u)
    # The sensor's frame of its first tick (t = PERIOD) reaches the actuator after its length at
    # 500 kbit/s (the bus's default), counted here from ISO 11898-1; the actuator's own frame (ID
    # 0x200) loses the arbitration at that tick and follows right after.
    first = can_bits(0x123, struct.pack("<d", u[0](PERIOD))) / 500_000
    second = can_bits(0x200, struct.pack("<d", 0.0)) / 500_000
    at0 = [(t - PERIOD, p, ops) for t, p, ops in deliveries if t < 1.5 * PERIOD]
    (t1, p1, ops1), (t1b, p1b, ops1b) = sorted(at0[:2], key=lambda d: d[1])
    assert abs(t1 - first) < 1e-12 and abs(t1b - first) < 1e-12, (t1, first)
    assert p1 == 1 and [c for c, _ in ops1] == [0x20] and struct.unpack("<I", ops1[0][1])[0] == 0x123  # Confirm
    assert p1b == 2 and [c for c, _ in ops1b] == [0x10]
    assert transmitted(ops1b[0][1])[3] == struct.pack("<d", u[0](PERIOD))
    t2 = [(t, p) for t, p, _ in at0[2:]]
    assert t2 and abs(t2[0][0] - (first + second)) < 1e-12, (t2, first + second)
    # Every period the same: the actuator outputs the sensor's signal of the last tick.
    assert actuator.get("y") == u[0](0.05) and actuator.get("frames_received") == 5
    assert sensor.get("confirmed") == 5 and actuator.get("confirmed") == 5
    assert bus.get("frames_delivered") == 10 and bus.get("arbitration_losses") == 0
    # The bus load: the bits of the ten frames (each counted here with its own data) over the time.
    busy = sum(can_bits(0x123, struct.pack("<d", u[0](k * PERIOD))) + can_bits(0x200, struct.pack("<d", 0.0))
               for k in range(1, 6)) / 500_000
    load = bus.get("bus_load")
    assert abs(load - busy / bus.t) < 1e-9, (load, busy / bus.t)
    for x in (sensor, actuator):
        x.close()


def test_injected_bus_errors_reach_every_node_and_the_frame_is_sent_again(can_signal, can_bus):
    sensor = Node(can_signal, "sensor", tx_id=0x123, rx_id=0x7FF, period=PERIOD, BusNotifications=True)
    actuator = Node(can_signal, "actuator", tx_id=0x200, rx_id=0x123, period=PERIOD, BusNotifications=True)
    sensor.period = actuator.period = PERIOD
    bus = Bus(can_bus, error_every=3)
    run_network([sensor, actuator], bus, 0.055, [lambda t: t, lambda t: 0.0])
    errors = bus.get("bus_errors")
    assert errors >= 3
    # Each error reached both nodes (one Bus Error each); every frame still arrived, later.
    assert sensor.get("bus_errors") == actuator.get("bus_errors") == errors
    assert bus.get("frames_delivered") == 10 and actuator.get("y") == 0.05
    for x in (sensor, actuator):
        x.close()


def test_the_bus_simulation_is_packaged_as_one(can_bus):
    path, md, _ = can_bus
    with zipfile.ZipFile(path) as z:
        manifest = etree.fromstring(z.read("extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml"))
        terminals = etree.fromstring(z.read("terminalsAndIcons/terminalsAndIcons.xml"))
    assert manifest.get("isBusSimulationFMU") == "true"
    assert [t.get("name") for t in terminals.findall("Terminals/Terminal")] == ["Node1", "Node2", "Node3", "Node4"]
    v = {x.name: x for x in md.modelVariables}
    assert all(v[f"Node{k}.Tx_Clock"].intervalVariability == "countdown" for k in range(1, 5))
    assert all((v[f"Node{k}.BusNotifications"].causality, v[f"Node{k}.BusNotifications"].variability)
               == ("output", "constant") for k in range(1, 5))
    out = subprocess.run([CARGO_FMU, "fmu", "check", "--strict", path], capture_output=True, text=True)
    assert out.returncode == 0 and " 0 failed, 0 warned" in out.stdout, out.stdout[-3000:]
