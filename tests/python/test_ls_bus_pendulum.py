"""Issue 55, item 3: the paper's pendulum as a networked control system. The CanSensor,
CanController (the ECU) and two CanMotorDrive network FMUs on the CanBus bus simulation, with the
Pendulum and two DCMotor FMUs, run by the scheduler of examples/ls_bus_loop.py on fmpy:

- the LQR of eq. (14) with the paper's gains stabilizes the pendulum through the bus, from the
  demos' initial state;
- with a fast bus and a short period its angles approach those of the direct loop (the
  SampledController wired to the same plant at the same period), within a bound computed here
  from the delay the bus adds and the signals' 16-bit scaling, through the closed loop's impulse
  response from the paper's linearization;
- every frame's arrival is its queueing and its bits at the baud rate, CAN's arbitration and bit
  count replayed here in Python (not taken from the Rust bus), with background traffic too;
- a malformed buffer, a frame of the wrong length and a frame that does not come leave the
  nodes' values as they were."""

import math
import struct
import sys

import numpy as np
import pytest
import scipy.linalg

from conftest import FMU_DIR, ROOT
import paper_model

sys.path.insert(0, str(ROOT / "examples"))
import ls_bus_loop as L  # noqa: E402

FMUS = FMU_DIR / "fmi3"
# The paper's printed gain, eq. (14) (../../shared/reference/paper-values.md).
PAPER_K = np.array([[14.0666, 2.8816, 1.1348, 1.0010], [-3.1814, 0.1161, 4.8456, 0.9957]])
# Fine scaling, so that the comparison with the direct loop is about the bus's delay: 1e-5 rad
# (+-0.33 rad), 1e-4 rad/s (+-3.3 rad/s), 2e-4 V (+-6.6 V, the supply's 6 V inside).
FINE = dict(angle_resolution=1e-5, rate_resolution=1e-4, voltage_resolution=2e-4)
TS = 1e-3


@pytest.fixture(scope="module")
def fast():
    cfg = L.Config(stop=2.0, sensor_period=TS, ecu_period=TS, baud=1_000_000, **FINE)
    run = L.networked(cfg, FMUS)
    return cfg, run, L.direct(TS, run.t, FMUS)


@pytest.fixture(scope="module")
def slower():
    cfg = L.Config(stop=1.0, sensor_period=TS, ecu_period=TS, baud=500_000, **FINE)
    run = L.networked(cfg, FMUS)
    return cfg, run, L.direct(TS, run.t, FMUS)


def angle_error(run, reference, until):
    """max |alpha_i(networked) - alpha_i(direct)| up to `until` (the direct run has every point of the networked)."""
    keep = run.t <= until + 1e-12
    at = np.searchsorted(reference.t, run.t[keep] - 1e-12)
    return np.abs(run.x[keep][:, [0, 2]] - reference.x[at][:, [0, 2]]).max()


def impulse_bounds(K):
    """Peak and L1 norm (over 5 s) of the closed loop's impulse response from the torques to the
    angles, the plant linearized here from paper_model (eqs. (6)-(7), written from the paper):
    (max_t max_i sum_j |g_ij(t)|, max_i sum_j int |g_ij| dt)."""
    f, e = (lambda x, m: paper_model.rhs(x, m[0], m[1])), 1e-6
    A = np.column_stack([(f(np.eye(4)[i] * e, [0, 0]) - f(-np.eye(4)[i] * e, [0, 0])) / (2 * e) for i in range(4)])
    B = np.column_stack([(f(np.zeros(4), np.eye(2)[i] * e) - f(np.zeros(4), -np.eye(2)[i] * e)) / (2 * e)
                         for i in range(2)])
    dt = 1e-3
    step, g, peak, l1 = scipy.linalg.expm((A - B @ K) * dt), B.copy(), 0.0, np.zeros(2)
    for _ in range(5000):
        rows = np.abs(g[[0, 2], :]).sum(axis=1)
        peak, l1 = max(peak, rows.max()), l1 + rows * dt
        g = step @ g
    return peak, l1.max()


def test_the_ecu_runs_the_papers_gain_and_the_bus_stabilizes_the_pendulum(fast):
    cfg, run, _ = fast
    K = np.array(run.counters["ecu.K"]).reshape(2, 4)
    assert np.allclose(K, PAPER_K, atol=5e-5), K
    assert not run.fallen
    alpha = np.abs(run.x[:, [0, 2]])
    assert alpha[0].tolist() == [0.1, 0.05]
    late = alpha[run.t >= 1.5].max()
    assert late < 0.01, f"max |alpha| over the last 0.5 s: {late} rad (from 0.1)"
    assert late < alpha[(run.t >= 1.0) & (run.t < 1.5)].max() < alpha[(run.t >= 0.5) & (run.t < 1.0)].max()
    # Every sample went through: each of 2000 sensor frames, 2 x 2000 commands.
    c = run.counters
    assert c["sensor.frames_sent"] == 2000 and c["ecu.frames_sent"] == 4000
    assert c["ecu.frames_received"] == c["drive1.frames_received"] == c["drive2.frames_received"] == 1999
    assert all(c[k] == 0 for k in c if k.endswith(("format_errors", "bad_frames", "signals_limited")))


def test_a_fast_bus_approaches_the_direct_loop_within_the_delay_it_adds(fast, slower):
    """The networked loop differs from the direct one by when the commands act: each command
    frame reaches its motor d <= d_max after the ECU's tick, where the direct controller's command
    acts at the tick; and by the 16-bit scaling. Through the closed loop (impulse response g from
    the torques to the angles) a torque difference dM gives an angle difference of at most
    peak|g| * int|dM| (short pulses) or ||g||_1 * max|dM| (a lasting one). The pulses: at each
    tick the command changes by |M_k - M_{k-1}| and the networked loop applies the change d later:
    int|dM| <= d_max * (total variation of M). The scaling: a measurement error of half a bit
    moves M by |K| q/2 (the voltage's half bit by n km / R q_U/2, the velocity's also through the
    voltage's feed-forward). The bound is doubled for what it leaves out (the continuous closed
    loop for the sampled one, the linearization at 0.1 rad)."""
    peak, l1 = impulse_bounds(PAPER_K)
    n, km, R, kb, B = 200.0, 0.00449, 2.22, 0.00448, 1e-6  # the demo motor (examples/ls_bus_loop.py)
    torque_per_volt = n * km / R
    q = np.array([FINE["angle_resolution"], FINE["rate_resolution"]] * 2) / 2
    feed_forward = n * n * B + n * n * km * kb / R  # N.m per rad/s of measured speed, through U
    dq = (np.abs(PAPER_K) @ q + feed_forward * q[1] + torque_per_volt * FINE["voltage_resolution"] / 2).max()
    errors = {}
    for name, (cfg, run, direct) in (("1 Mbit/s", fast), ("500 kbit/s", slower)):
        d_max = max(f.latency for f in run.frames if f.id in (L.MOTOR1_ID, L.MOTOR2_ID))
        total_variation = (np.abs(np.diff(direct.U, axis=0)).sum(axis=0) * torque_per_volt).sum()
        bound = 2 * (peak * d_max * total_variation + l1 * dq)
        error = angle_error(run, direct, cfg.stop)
        assert error <= bound, f"{name}: |alpha - alpha_direct| up to {error} rad, bound {bound} (d_max {d_max} s)"
        # The bound is not vacuous: well below the angles themselves.
        assert bound < 0.01
        errors[name] = angle_error(run, direct, 1.0)
    # The faster bus is the closer: its commands come sooner.
    assert errors["1 Mbit/s"] < errors["500 kbit/s"], errors


def replay_can(frames, baud, until):
    """Arrival of each frame, CAN written here: frames queued at their times; when the bus gets
    free, those queued before meet in the arbitration (lowest identifier first, then the first
    queued); an idle bus takes the frames of the next instant together; a frame occupies the bus
    for can_bits at the baud rate and arrives at its end. frames: [(queued, id, data)]."""
    queue = sorted(range(len(frames)), key=lambda k: (frames[k][0], k))
    arrival, pending, free, i = [math.nan] * len(frames), [], 0.0, 0
    while (i < len(queue) or pending) and free <= until:
        while i < len(queue) and frames[queue[i]][0] < free - 1e-12:
            pending.append(queue[i])
            i += 1
        if pending:
            start = free
        else:
            start = frames[queue[i]][0]
            while i < len(queue) and abs(frames[queue[i]][0] - start) < 1e-12:
                pending.append(queue[i])
                i += 1
        win = min(pending, key=lambda k: (frames[k][1], k))
        pending.remove(win)
        free = start + L.can_bits(frames[win][1], frames[win][2]) / baud
        arrival[win] = free
    return arrival


def check_latencies(cfg, run, background=()):
    mine = [(f.sent, f.id, f.data) for f in run.frames]
    arrival = replay_can(mine + list(background), cfg.baud, run.t[-1] + 1.0)
    last = run.t[-1]
    for f, want in zip(run.frames, arrival):
        if math.isnan(f.arrived):
            assert want > last - 1e-9, (f, want)
        else:
            assert abs(f.arrived - want) < 1e-9, (f, want)
    return np.array([f.latency for f in run.frames if not math.isnan(f.arrived)])


def test_each_frame_arrives_after_its_queueing_and_its_bits_at_the_baud_rate(fast, slower):
    for cfg, run, _ in (fast, slower):
        latency = check_latencies(cfg, run)
        # The commands (0x010, 0x011) win the arbitration over the measurement (0x020) of the
        # same tick: the measurement waits for both.
        sensor = [f.latency for f in run.frames if f.id == L.SENSOR_ID]
        assert min(sensor) > 2 * 60 / cfg.baud and latency.min() >= 40 / cfg.baud


def test_background_frames_of_higher_priority_delay_the_loops_frames_as_can_says():
    cfg = L.Config(stop=0.2, sensor_period=0.005, ecu_period=0.005, baud=250_000, background_load=0.6)
    run = L.networked(cfg, FMUS)
    # The CanBus's background: 8 bytes 0x55, identifier 0, one every bits / (baud * load), from
    # one such period after the start.
    data = bytes([0x55] * 8)
    period = L.can_bits(0, data) / cfg.baud / cfg.background_load
    background = [(k * period, 0, data) for k in range(1, int(cfg.stop / period) + 2)]
    latency = check_latencies(cfg, run, background)
    quiet = L.networked(L.Config(stop=0.2, sensor_period=0.005, ecu_period=0.005, baud=250_000), FMUS)
    assert latency.mean() > 1.2 * np.nanmean([f.latency for f in quiet.frames]), "the load adds waiting"
    load = run.bus_load[-1]
    assert 0.6 < load < 0.6 + 1.2 * quiet.bus_load[-1], load
    assert not run.fallen


# --- The nodes alone: what a malformed or missing frame leaves ---------------------------------

def test_the_ecu_keeps_its_last_measurement_through_a_bad_frame_and_a_malformed_buffer():
    ecu = L.Node(FMUS / "CanController.fmu", "ecu", dict(L.LAW, period=TS))
    good = measurement_frame(L.SENSOR_ID, [1000, -200, -500, 30])  # 0.1 rad, -0.2 rad/s, ...
    ecu.receive(good)
    assert ecu.floats(L.STATE) == pytest.approx([0.1, -0.2, -0.05, 0.03])
    short = can_transmit(L.SENSOR_ID, bytes(7))
    malformed = good + struct.pack("<II", 0x41, 9) + b"\x09"  # Status of a kind the standard lacks
    ecu.receive(short)
    ecu.receive(malformed)
    assert ecu.floats(L.STATE) == pytest.approx([0.1, -0.2, -0.05, 0.03]), "the last measurement is kept"
    assert (ecu.get("bad_frames"), ecu.get("format_errors"), ecu.get("frames_received")) == (1, 1, 1)
    # Its next tick: the Format Error (0x01, the offending operation as its data), then the two
    # commands computed from the kept measurement: M = -K x, U = R/(n km) (M + n^2 B omega) + n kb omega
    # (the Controller's voltage for the demo motor of examples/ls_bus_loop.py).
    ecu.step(0.0, TS)
    ops = L.operations(ecu.send())
    assert [c for c, _ in ops] == [0x01, 0x10, 0x10]
    K = np.array(ecu.f.getFloat64([ecu.vr("K")], nValues=8)).reshape(2, 4)
    x = np.array([0.1, -0.2, -0.05, 0.03])
    M = -K @ x
    U = 2.22 / (200 * 0.00449) * (M + 200 * 200 * 1e-6 * x[[1, 3]]) + 200 * 0.00448 * x[[1, 3]]
    sent = [struct.unpack("<h", a[8:10])[0] * 1e-3 for c, a in ops if c == 0x10]
    assert sent == pytest.approx(U, abs=0.5e-3 + 1e-12)
    ecu.close()


def test_a_drive_holds_its_voltage_until_the_next_good_frame_of_its_identifier():
    drive = L.Node(FMUS / "CanMotorDrive.fmu", "drive", dict(rx_id=L.MOTOR2_ID))
    assert drive.next_tx is None, "it sends nothing of its own"
    drive.receive(can_transmit(L.MOTOR2_ID, struct.pack("<h", -2500)))
    assert drive.get("U") == pytest.approx(-2.5)
    drive.receive(can_transmit(L.MOTOR1_ID, struct.pack("<h", 1000)))  # the other motor's
    drive.receive(can_transmit(L.MOTOR2_ID, struct.pack("<hh", 1, 2)))  # 4 bytes: not a command
    assert drive.get("U") == pytest.approx(-2.5) and drive.get("bad_frames") == 1
    drive.receive(b"\x10\x00\x00\x00\x05\x00\x00\x00")  # a Length shorter than a header
    assert drive.get("format_errors") == 1 and drive.get("U") == pytest.approx(-2.5)
    # The Format Error goes out at the tick it announced (reply_delay, 1 us).
    assert drive.next_tx == pytest.approx(1e-6)
    drive.step(0.0, 1e-6)
    [(code, args)] = L.operations(drive.send())
    assert code == 0x01 and args[2:] == b"\x10\x00\x00\x00\x05\x00\x00\x00"
    drive.close()


def test_the_sensor_sends_its_inputs_in_the_documented_layout():
    sensor = L.Node(FMUS / "CanSensor.fmu", "sensor", dict(period=0.002, tx_id=0x123))
    assert sensor.next_tx == pytest.approx(0.002)
    sensor.step(0.0, 0.002)
    [(can_id, data)] = L.frames(sensor.send(dict(alpha1=0.1, omega1=-1.23456, alpha2=-4.0, omega2=0.0004)))
    # int16 little-endian: alpha in 1e-4 rad, omega in 1e-3 rad/s; -4 rad is beyond the range.
    assert can_id == 0x123 and struct.unpack("<4h", data) == (1000, -1235, -32767, 0)
    assert sensor.get("signals_limited") == 1 and sensor.next_tx == pytest.approx(0.004)
    sensor.close()


def can_transmit(can_id, data):
    return struct.pack("<IIIBBH", 0x10, 16 + len(data), can_id, 0, 0, len(data)) + data


def measurement_frame(can_id, raw):
    return can_transmit(can_id, struct.pack("<4h", *raw))
