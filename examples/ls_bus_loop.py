"""The paper's pendulum as a networked control system (issue 55), run by an importer's scheduler
written here on fmpy: the Pendulum and two DCMotor FMUs (the plant, exchanged every `h`), and
four FMI-LS-BUS network FMUs on the CanBus bus simulation FMU:

    port 1  CanSensor      samples alpha1, omega1, alpha2, omega2 every sensor period, frame 0x020
    port 2  CanController  the LQR of eq. (14) every ECU period on the last measurement received,
                           U1 in frame 0x010, U2 in frame 0x011
    port 3  CanMotorDrive  U of frame 0x010 -> motor1.U (held)
    port 4  CanMotorDrive  U of frame 0x011 -> motor2.U (held)

The scheduler does what the layered standard describes for an importer with a bus simulation:
every network FMU (and the bus) announces its next bus communication point through the
countdown interval of its Tx clock (fmi3GetIntervalDecimal, qualifier fmi3IntervalChanged); at
that time, in Event Mode, its Tx clock is activated and its Tx_Data read; the Tx_Data of every
node that sent at one instant go into the bus's port Rx_Data in one event (so that they meet in
one arbitration); at the bus's own ticks its port Tx_Data go into the nodes' Rx_Data. Between
these instants, and at least every `h`, every FMU does a step.

`direct(...)` runs the same plant and motors with the SampledController FMU wired to them (the
same control law at the same period, no bus): the un-networked loop. Both loops see their first
measurement at t = Ts: the sensor's countdown ticks first one period after the start, and the
direct controller's tick at t = 0 is given no measurement (zeros), so the direct controller's
tick k applies the sample of tick k - 1 exactly as the ECU applies the sensor frame of its
previous tick; what differs is the bus: the frames' times on it, and the 16-bit scaling.

Used by tests/python/test_ls_bus_pendulum.py and examples/ls_bus_study.py.
"""

import collections
import ctypes
import dataclasses
import functools
import math
import os
import pathlib
import struct

import fmpy
import numpy as np
from fmpy.fmi3 import FMU3Slave

ROOT = pathlib.Path(__file__).resolve().parents[1]
FMU_DIR = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "fmu" / "fmi3"

# The demos' initial state (holonomic/systems.toml; the paper starts from rest upright).
PLANT = dict(alpha1_0=0.1, alpha2_0=-0.05)
# The demo motor of holonomic/systems.toml: the paper's electrical constants, a 200:1 gearbox and
# a small motor's viscous friction (the paper's motors cannot hold the pendulum). The rotor
# inertia (n^2 J at the joint) is left out of the plant here, as the paper's eqs. (6)-(7) have
# none: the LQR gain of eq. (14) with the paper's numbers is then designed for this very plant.
MOTOR = dict(coupled=True, gear_ratio=200.0, B=1e-6)
# The control law, both loops: the LQR of eq. (14) (mode 1), voltages for the motors above.
LAW = dict(mode=1, gear_ratio=200.0, motor_B=1e-6, drives_motors=True)
SENSOR_ID, MOTOR1_ID, MOTOR2_ID = 0x020, 0x010, 0x011
STATE = ("alpha1", "omega1", "alpha2", "omega2")
CAN_TRANSMIT = 0x10
INTERVAL_CHANGED = 2  # fmi3IntervalChanged
EPS = 1e-12


@dataclasses.dataclass
class Config:
    """One networked run. Periods [s], baud rate [bit/s], background load [share of the bus]."""

    stop: float = 3.0
    h: float = 1e-3
    sensor_period: float = 0.01
    ecu_period: float = 0.01
    baud: int = 500_000
    background_load: float = 0.0
    angle_resolution: float = 1e-4
    rate_resolution: float = 1e-3
    voltage_resolution: float = 1e-3
    # Stop early once an angle is beyond this [rad]: the pendulum has fallen.
    fallen: float = math.pi / 2


def operations(buffer):
    """The bus operations of a Tx/Rx_Data value, read with `struct` from the standard's table
    (OP Code, Length, arguments; little-endian): [(op code, arguments)]."""
    out, at = [], 0
    while at < len(buffer):
        code, length = struct.unpack_from("<II", buffer, at)
        assert 8 <= length <= len(buffer) - at, (at, length, buffer.hex())
        out.append((code, bytes(buffer[at + 8:at + length])))
        at += length
    return out


def frames(buffer):
    """The CAN frames of a buffer: [(identifier, data)] (CAN Transmit: ID, Ide, Rtr, Data Length, Data)."""
    out = []
    for code, args in operations(buffer):
        if code == CAN_TRANSMIT:
            can_id, _ide, _rtr, n = struct.unpack_from("<IBBH", args)
            out.append((can_id, args[8:8 + n]))
    return out


@functools.lru_cache(maxsize=None)
def _unpacked(path):
    return fmpy.read_model_description(path), fmpy.extract(path)


class Instance:
    """One FMI 3.0 co-simulation instance: start values typed by the description."""

    def __init__(self, path, name, start=None, event_mode=False):
        md, unzipped = _unpacked(str(path))
        self.var = {v.name: v for v in md.modelVariables}
        self.f = FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                           instanceName=name)
        self.f.instantiate(eventModeUsed=event_mode)
        self.event_mode = event_mode
        self.f.enterInitializationMode(startTime=0.0)
        for k, v in (start or {}).items():
            self.set(k, v)
        self.f.exitInitializationMode()
        self.t = 0.0

    def vr(self, name):
        return self.var[name].valueReference

    def set(self, name, value):
        kind = self.var[name].type
        if kind == "Float64":
            self.f.setFloat64([self.vr(name)], [float(value)])
        elif kind == "Boolean":
            self.f.setBoolean([self.vr(name)], [bool(value)])
        elif kind in ("Int64", "Enumeration"):
            self.f.setInt64([self.vr(name)], [int(value)])
        else:
            self.f.setInt32([self.vr(name)], [int(value)])

    def get(self, name):
        kind = self.var[name].type
        if kind == "Float64":
            return self.f.getFloat64([self.vr(name)])[0]
        if kind in ("Int64", "Enumeration"):
            return self.f.getInt64([self.vr(name)])[0]
        return self.f.getInt32([self.vr(name)])[0]

    def floats(self, names):
        return self.f.getFloat64([self.vr(n) for n in names])

    def step(self, t, dt):
        if self.event_mode:
            self.f.enterStepMode()
        event, terminate, early, _ = self.f.doStep(t, dt)
        assert not terminate and not early
        if self.event_mode:
            self.f.enterEventMode()
        self.t = t + dt

    def settle(self):
        while self.f.updateDiscreteStates()[0]:
            pass

    def close(self):
        self.f.terminate()
        self.f.freeInstance()


class Node(Instance):
    """A network FMU (or the bus simulation) whose countdown Tx clock(s) announce its next bus
    communication point: `next_tx`, read after every event."""

    def __init__(self, path, name, start=None, tx_clock="CAN.Tx_Clock"):
        self.tx_clock = tx_clock
        self.next_tx = None
        super().__init__(path, name, start, event_mode=True)
        self.announced()

    def announced(self):
        vrs = (ctypes.c_uint32 * 1)(self.vr(self.tx_clock))
        interval, qualifier = (ctypes.c_double * 1)(), (ctypes.c_int * 1)()
        self.f.getIntervalDecimal(vrs, interval, qualifier)
        if qualifier[0] == INTERVAL_CHANGED:
            self.next_tx = self.t + interval[0]

    def event(self):
        self.settle()
        self.announced()

    def send(self, inputs=None):
        """A Tx tick: inputs set, Tx_Clock activated; the Tx_Data it gives."""
        self.f.setClock([self.vr(self.tx_clock)], [True])
        for k, v in (inputs or {}).items():
            self.set(k, v)
        # A clocked output is read while its clock is active, before the update ends the tick.
        tx = self.f.getBinary([self.vr("CAN.Tx_Data")])[0]
        self.next_tx = None
        self.event()
        return tx

    def receive(self, data):
        self.f.setClock([self.vr("CAN.Rx_Clock")], [True])
        self.f.setBinary([self.vr("CAN.Rx_Data")], [data])
        self.event()


class Bus(Node):
    """The CanBus instance, ports 1..4: its four countdown Tx clocks tick together."""

    def __init__(self, path, start):
        super().__init__(path, "bus", start, tx_clock="Node1.Tx_Clock")

    def receive_all(self, sent):
        """The Tx_Data of the nodes that sent at one instant ({port: bytes}), in one event."""
        ports = sorted(sent)
        self.f.setClock([self.vr(f"Node{p}.Rx_Clock") for p in ports], [True] * len(ports))
        self.f.setBinary([self.vr(f"Node{p}.Rx_Data") for p in ports], [sent[p] for p in ports])
        self.event()

    def deliver(self, sent=None):
        """The bus's tick: {port: the bus operations it gets}. The Tx_Data of the nodes that sent
        at the same instant (`sent`, as in receive_all) arrive in the same event: the tick the bus
        announced is activated at its time (FMI 3.0.2, countdown Clocks), its Rx_Clocks with it."""
        ports = [1, 2, 3, 4]
        self.f.setClock([self.vr(f"Node{p}.Tx_Clock") for p in ports], [True] * 4)
        if sent:
            rx = sorted(sent)
            self.f.setClock([self.vr(f"Node{p}.Rx_Clock") for p in rx], [True] * len(rx))
            self.f.setBinary([self.vr(f"Node{p}.Rx_Data") for p in rx], [sent[p] for p in rx])
        out = {p: self.f.getBinary([self.vr(f"Node{p}.Tx_Data")])[0] for p in ports}
        self.next_tx = None
        self.event()
        return out


@dataclasses.dataclass
class Frame:
    """A frame a node sent: when its Tx_Data went to the bus, when the bus delivered it."""

    id: int
    data: bytes
    sent: float
    port: int
    arrived: float = math.nan

    @property
    def latency(self):
        return self.arrived - self.sent


@dataclasses.dataclass
class Run:
    t: np.ndarray  # the time points [s]
    x: np.ndarray  # (alpha1, omega1, alpha2, omega2) at them
    U: np.ndarray  # the motors' voltage commands at them [V]
    frames: list  # [Frame], every node's frame (none of the background)
    bus_load: np.ndarray = None  # the CanBus's bus_load output at the time points
    counters: dict = dataclasses.field(default_factory=dict)
    fallen: bool = False

    def angles(self, at):
        """alpha1, alpha2 interpolated at the times `at`."""
        return np.column_stack([np.interp(at, self.t, self.x[:, k]) for k in (0, 2)])


class Plant:
    """The Pendulum and the two DCMotors, coupled every time point: the joint speeds into the
    motors, the motors' joint torques into the pendulum."""

    def __init__(self, fmu_dir, plant=None, motor=None):
        self.pendulum = Instance(fmu_dir / "Pendulum.fmu", "pendulum", {**PLANT, **(plant or {})})
        self.motors = [Instance(fmu_dir / "DCMotor.fmu", f"motor{i}", {**MOTOR, **(motor or {})}) for i in (1, 2)]

    def state(self):
        return self.pendulum.floats(STATE)

    def couple(self, x, U):
        for motor, omega, u in zip(self.motors, (x[1], x[3]), U):
            motor.set("omega", omega)
            motor.set("U", u)
        torques = [m.get("tau") for m in self.motors]
        self.pendulum.f.setFloat64([self.pendulum.vr("M1"), self.pendulum.vr("M2")], torques)

    def step(self, t, dt):
        for c in (self.pendulum, *self.motors):
            c.step(t, dt)

    def close(self):
        for c in (self.pendulum, *self.motors):
            c.close()


def next_grid(t, h):
    return (math.floor(t / h + 1e-9) + 1) * h


def networked(cfg=Config(), fmu_dir=FMU_DIR, plant=None, motor=None, law=None):
    """The networked loop of `cfg`: a Run with every node's frames and their latencies."""
    fmu_dir = pathlib.Path(fmu_dir)
    p = Plant(fmu_dir, plant, motor)
    scaling = dict(angle_resolution=cfg.angle_resolution, rate_resolution=cfg.rate_resolution)
    sensor = Node(fmu_dir / "CanSensor.fmu", "sensor", dict(period=cfg.sensor_period, tx_id=SENSOR_ID, **scaling))
    ecu = Node(fmu_dir / "CanController.fmu", "ecu", {**LAW, **(law or {}), "period": cfg.ecu_period,
                                                      "sensor_id": SENSOR_ID, "motor1_id": MOTOR1_ID,
                                                      "motor2_id": MOTOR2_ID,
                                                      "voltage_resolution": cfg.voltage_resolution, **scaling})
    drives = [Node(fmu_dir / "CanMotorDrive.fmu", f"drive{i}", dict(rx_id=rx, voltage_resolution=cfg.voltage_resolution))
              for i, rx in ((1, MOTOR1_ID), (2, MOTOR2_ID))]
    bus = Bus(fmu_dir / "CanBus.fmu", dict(baud_rate=cfg.baud, background_load=cfg.background_load))
    nodes = [sensor, ecu, *drives]  # port k + 1
    ts, xs, us, loads, sent_frames = [], [], [], [], []
    in_flight = collections.defaultdict(collections.deque)
    t, fallen = 0.0, False
    while True:
        x = p.state()
        # Whether the bus's announced tick is now, known before anything happens at this instant
        # (the Rx event of the frames sent now may announce another interval: the tick announced
        # for now is activated all the same, in that event).
        bus_due = bus.next_tx is not None and abs(bus.next_tx - t) < EPS
        # The nodes whose Tx clock ticks now send; their frames meet at the bus in one event.
        sent = {}
        for k, node in enumerate(nodes):
            if node.next_tx is not None and abs(node.next_tx - t) < EPS:
                tx = node.send(dict(zip(STATE, x)) if node is sensor else None)
                if tx:
                    sent[k + 1] = tx
                    for can_id, data in frames(tx):
                        f = Frame(can_id, data, t, k + 1)
                        sent_frames.append(f)
                        in_flight[can_id].append(f)
        if sent and not bus_due:
            bus.receive_all(sent)
        # The bus's tick: what each port gets (a frame goes to every port but its sender's). A
        # node that sent now receives after its Tx_Data was read, in an event of its own
        # (FMI-LS-BUS 1.0.0, 4: the Rx_Clock activated "respecting the Tx_Data and Rx_Data dependency").
        if bus_due:
            delivered = bus.deliver(sent)
            arrived = collections.Counter()
            for port, data in delivered.items():
                if data:
                    nodes[port - 1].receive(data)
                    counts = collections.Counter(can_id for can_id, _ in frames(data))
                    for can_id, n in counts.items():
                        arrived[can_id] = max(arrived[can_id], n)
            for can_id, n in arrived.items():
                for _ in range(n):
                    if in_flight[can_id]:
                        in_flight[can_id].popleft().arrived = t
        U = [d.get("U") for d in drives]
        p.couple(x, U)
        ts.append(t)
        xs.append(x)
        us.append(U)
        loads.append(bus.get("bus_load"))
        if max(abs(x[0]), abs(x[2])) > cfg.fallen:
            fallen = True
            break
        if t >= cfg.stop - EPS:
            break
        t_next = min([next_grid(t, cfg.h), cfg.stop] + [n.next_tx for n in (*nodes, bus) if n.next_tx is not None])
        dt = t_next - t
        p.step(t, dt)
        for n in (*nodes, bus):
            n.step(t, dt)
        t = t_next
    counters = {f"{name}.{c}": n.get(c) for name, n, cs in (
        ("sensor", sensor, ("frames_sent", "format_errors", "signals_limited")),
        ("ecu", ecu, ("frames_received", "frames_sent", "format_errors", "bad_frames", "signals_limited")),
        ("drive1", drives[0], ("frames_received", "format_errors", "bad_frames")),
        ("drive2", drives[1], ("frames_received", "format_errors", "bad_frames")),
        ("bus", bus, ("frames_delivered", "bus_errors", "arbitration_losses"))) for c in cs}
    counters["ecu.K"] = list(ecu.f.getFloat64([ecu.vr("K")], nValues=8))
    for c in (p, *nodes, bus):
        c.close()
    return Run(np.array(ts), np.array(xs), np.array(us), sent_frames, np.array(loads), counters, fallen)


def direct(Ts, times, fmu_dir=FMU_DIR, plant=None, motor=None, law=None):
    """The un-networked loop: the SampledController (period Ts) wired to the plant, on the time
    points `times` (those of a networked run, so that the plant is exchanged at the same points),
    its ticks at k Ts among them."""
    fmu_dir = pathlib.Path(fmu_dir)
    p = Plant(fmu_dir, plant, motor)
    c = Instance(fmu_dir / "SampledController.fmu", "controller", {**LAW, **(law or {}), "Ts": Ts}, event_mode=True)
    grid = np.union1d(np.asarray(times), np.arange(0.0, times[-1] + Ts / 2, Ts))
    # Points closer than EPS are one point.
    grid = grid[np.concatenate([[True], np.diff(grid) > 1e-10])]
    inputs = [c.vr(n) for n in STATE]
    outputs = [c.vr("U1"), c.vr("U2")]
    xs, us, U, k = [], [], [0.0, 0.0], 0
    for i, t in enumerate(grid):
        x = p.state()
        if abs(t - k * Ts) < 1e-10:
            c.f.setClock([c.vr("sample")], [True])
            c.f.setFloat64(inputs, x if k > 0 else [0.0] * 4)
            U = c.f.getFloat64(outputs)
            c.settle()
            k += 1
        p.couple(x, U)
        xs.append(x)
        us.append(U)
        if i + 1 < len(grid):
            dt = grid[i + 1] - t
            p.step(t, dt)
            c.step(t, dt)
    p.close()
    c.close()
    return Run(grid, np.array(xs), np.array(us), [])


def can_bits(can_id, data):
    """A classic standard CAN data frame's length in bits, from ISO 11898-1: start of frame ..
    CRC-15, stuffed (a bit of opposite value after five equal ones), then CRC delimiter, ACK slot
    and delimiter, end of frame (7), intermission (3). Written here, not taken from the Rust code."""
    bits = [0] + [(can_id >> i) & 1 for i in range(10, -1, -1)] + [0, 0, 0]  # SOF, ID, RTR, IDE, r0
    bits += [(len(data) >> i) & 1 for i in range(3, -1, -1)]
    for byte in data:
        bits += [(byte >> i) & 1 for i in range(7, -1, -1)]
    crc = 0
    for b in bits:
        nxt = b ^ ((crc >> 14) & 1)
        crc = (crc << 1) & 0x7FFF
        if nxt:
            crc ^= 0x4599
    bits += [(crc >> i) & 1 for i in range(14, -1, -1)]
    stuffed, run, last = 0, 0, None
    for b in bits:
        run = run + 1 if b == last else 1
        last = b
        if run == 5:
            stuffed, last, run = stuffed + 1, 1 - b, 1
    return len(bits) + stuffed + 13


def added_delay(run, ecu_period):
    """For every command frame that arrived: how much older its measurement is when it reaches
    the motor than in the direct loop (where the command of tick k, from the sample of tick k - 1,
    acts at tick k: an age of one period). The measurement a command used is the last sensor frame
    that arrived before the ECU's tick (at the same instant the ECU sends first)."""
    sensor = sorted((f.arrived, f.sent) for f in run.frames if f.id == SENSOR_ID and not math.isnan(f.arrived))
    arrivals = np.array([a for a, _ in sensor])
    samples = np.array([s for _, s in sensor])
    out = []
    for f in run.frames:
        if f.id in (MOTOR1_ID, MOTOR2_ID) and not math.isnan(f.arrived):
            k = np.searchsorted(arrivals, f.sent - EPS) - 1  # arrivals strictly before the tick
            if k >= 0:
                out.append(f.arrived - samples[k] - ecu_period)
    return np.array(out)
