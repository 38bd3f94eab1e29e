"""Issue 24: events. The Reference-FMUs' event models written with rustfmu
(reference-fmus/): BouncingBall (a state event at the floor) and Stair (time events
every second), and the plain Dahlquist and VanDerPol, in fmpy's Model Exchange (CVode, Euler) and
Co-Simulation (the runtime's integrator, which locates state events on its dense output), FMI 2.0
and 3.0, against the analytic answers."""

import math

import fmpy
import numpy as np
import pytest

from conftest import fmu, fmu3

G, E, V_MIN, H0 = 9.81, 0.7, 0.1, 1.0


def bounces():
    """The analytic bounce sequence of the ball dropped from H0: (time, speed after) of every
    bounce, the last one leaving it at rest (its speed after would be below V_MIN)."""
    t, v_hit = math.sqrt(2 * H0 / G), math.sqrt(2 * G * H0)
    out = []
    while True:
        v_up = E * v_hit
        out.append((t, 0.0 if v_up < V_MIN else v_up))
        if v_up < V_MIN:
            return out
        t += 2 * v_up / G
        v_hit = v_up


def ball(t):
    """Height and velocity of the analytic ball at time t."""
    seq = bounces()
    if t < seq[0][0]:
        return H0 - G * t * t / 2, -G * t
    for (tb, v_up), nxt in zip(seq, seq[1:] + [(math.inf, 0.0)]):
        if tb <= t < nxt[0]:
            if v_up == 0.0:
                return 0.0, 0.0
            s = t - tb
            return v_up * s - G * s * s / 2, v_up - G * s
    return 0.0, 0.0


def analytic(times):
    hv = np.array([ball(t) for t in times])
    return hv[:, 0], hv[:, 1]


@pytest.fixture(scope="module", params=["2.0", "3.0"])
def bouncing_ball(request):
    return fmu("BouncingBall") if request.param == "2.0" else fmu3("BouncingBall")


def simulate(path, **kw):
    return fmpy.simulate_fmu(path, stop_time=3.0, output=["h", "v"], **kw)


def test_the_analytic_ball_bounces_eleven_times_and_rests_before_3_s():
    seq = bounces()
    assert len(seq) == 11 and seq[-1][1] == 0.0 and 2.4 < seq[-1][0] < 2.6, seq


@pytest.mark.parametrize("step", [1e-2, 1e-3])
def test_co_simulation_locates_every_bounce_to_1e_9_s(bouncing_ball, step):
    """The runtime's integrator stops at the floor inside the step: the states at every
    communication point are those of the exact trajectory. A bounce located δ late would show as an
    error of about (1 + e) g δ in the velocity after it: the velocities agree to 2e-8 m/s, so every
    bounce is located within 1e-9 s. The ball is never below the floor and rests at the end."""
    r = simulate(bouncing_ball, fmi_type="CoSimulation", output_interval=step)
    h, v = analytic(r["time"])
    assert np.max(np.abs(r["h"] - h)) < 1e-9, np.max(np.abs(r["h"] - h))
    assert np.max(np.abs(r["v"] - v)) < 2e-8, np.max(np.abs(r["v"] - v))
    assert r["h"].min() >= 0.0
    assert r["v"][-1] == 0.0 and 0.0 <= r["h"][-1] < 1e-300


def test_model_exchange_with_cvode_bounces_where_the_formula_says(bouncing_ball):
    """fmpy's CVode (rtol 1e-8) finds the floor through the event indicator h: all eleven bounces
    within 1e-5 s of the analytic times (the location errors add up over the bounces), the states
    between them within the tolerance, the ball below the floor only by CVode's root tolerance,
    and at rest after the eleventh bounce."""
    r = simulate(bouncing_ball, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8,
                 output_interval=1e-3)
    # fmpy records the values before and after each event at its time: the events are the
    # times recorded twice.
    events = r["time"][1:][np.diff(r["time"]) == 0]
    seq = [tb for tb, _ in bounces()]
    assert len(events) == len(seq), (events, seq)
    assert np.max(np.abs(events - seq)) < 1e-5, np.max(np.abs(events - seq))
    away = np.array([min(abs(t - tb) for tb in seq) > 1e-5 for t in r["time"]])
    h, v = analytic(r["time"])
    assert np.max(np.abs(r["h"] - h)[away]) < 1e-5, np.max(np.abs(r["h"] - h)[away])
    assert np.max(np.abs(r["v"] - v)[away]) < 1e-4, np.max(np.abs(r["v"] - v)[away])
    assert r["h"].min() > -1e-9, r["h"].min()
    assert r["v"][-1] == 0.0 and r["h"][-1] >= 0.0


def test_model_exchange_with_euler_bounces_instead_of_falling_through(bouncing_ball):
    """fmpy's Euler (1 ms) detects the sign change of h after the step that crosses the floor:
    the ball bounces every time (below the floor by at most one step's fall) and its first bounce
    is where the formula says, within the step."""
    r = simulate(bouncing_ball, fmi_type="ModelExchange", solver="Euler", step_size=1e-3, output_interval=1e-3)
    assert r["h"].min() > -G * 0.5 * 1e-3, r["h"].min()
    first = r["time"][np.argmax(r["v"] > 0)]
    assert abs(first - bounces()[0][0]) <= 2e-3, first
    # It bounces again and again: the first apexes within 5 % of e^2k h0 (Euler's own error).
    ups = np.flatnonzero((r["v"][:-1] > 0) & (r["v"][1:] <= 0))
    assert len(ups) >= 8, ups
    for k, i in enumerate(ups[:3], start=1):
        assert abs(r["h"][i] - E ** (2 * k) * H0) < 0.05 * E ** (2 * k) * H0, (k, r["h"][i])


def test_fmi3_runs_are_equal_to_fmi2_runs():
    """One binary, two descriptions: every result equal bit for bit."""
    for kw in (dict(fmi_type="CoSimulation", output_interval=1e-2),
               dict(fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8, output_interval=1e-2)):
        a, b = simulate(fmu("BouncingBall"), **kw), simulate(fmu3("BouncingBall"), **kw)
        assert len(a) == len(b)
        for name in ("time", "h", "v"):
            assert np.array_equal(a[name], b[name]), (kw, name)


@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("fmi_type", ["ModelExchange", "CoSimulation"])
def test_stair_counts_every_second_and_ends_the_simulation_at_ten(version, fmi_type):
    """Time events at every whole second: counter = floor(t) + 1, and at t = 9 the model ends the
    simulation (counter 10), as the Reference-FMUs' Stair does."""
    path = fmu("Stair") if version == "2.0" else fmu3("Stair")
    r = fmpy.simulate_fmu(path, fmi_type=fmi_type, stop_time=10.0, output_interval=0.1, output=["counter"])
    assert r["time"][-1] == pytest.approx(9.0, abs=1e-9), r["time"][-1]
    for t, c in zip(r["time"], r["counter"]):
        # Between the events (fmpy records both sides of an event at its time).
        if abs(t - round(t)) > 1e-6:
            assert c == math.floor(t) + 1, (t, c)
    # The count at the end: 10 in co-simulation (the step ends after the event); model exchange
    # records the value before the event at its time, then stops.
    assert r["counter"][-1] == (10 if fmi_type == "CoSimulation" else 9)


@pytest.mark.parametrize("fmi_type", ["ModelExchange", "CoSimulation"])
def test_dahlquist_follows_the_exponential(fmi_type):
    path = fmu("Dahlquist")
    r = fmpy.simulate_fmu(path, fmi_type=fmi_type, stop_time=10.0, output_interval=0.1, relative_tolerance=1e-8,
                          output=["x"])
    assert np.max(np.abs(r["x"] - np.exp(-r["time"]))) < 1e-6


def test_van_der_pol_agrees_between_the_interfaces_and_versions():
    kw = dict(stop_time=20.0, output_interval=0.01, relative_tolerance=1e-9, output=["x0", "x1"])
    me = fmpy.simulate_fmu(fmu("VanDerPol"), fmi_type="ModelExchange", **kw)
    cs = fmpy.simulate_fmu(fmu("VanDerPol"), fmi_type="CoSimulation", **kw)
    cs3 = fmpy.simulate_fmu(fmu3("VanDerPol"), fmi_type="CoSimulation", **kw)
    assert np.max(np.abs(me["x0"] - cs["x0"])) < 1e-5
    assert np.array_equal(cs["x0"], cs3["x0"])
    # A limit cycle of amplitude about 2.
    assert 1.9 < np.max(np.abs(cs["x0"][len(cs) // 2:])) < 2.1


def test_the_controllers_torque_limit_is_a_state_event_in_model_exchange():
    """The paper's Controller declares its limits as event indicators (M1_margin ... U2_margin):
    CVode stops where the PID demand reaches M_max (t = 12 s for alpha1 = 0.1 rad held, Kp1 = 8,
    Ki1 = 1, M_max = 2) and the anti-windup's integral is held from there, as the analytic answer
    says (examples/controller_limit_events.py measures the same with and without the indicators)."""
    start = {"mode": 2, "M_max": 2.0, "Kp1": 8.0, "Ki1": 1.0, "alpha1": 0.1}
    r = fmpy.simulate_fmu(fmu("Controller"), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-6,
                          stop_time=20.0, output_interval=1e-2, start_values=start, output=["integral1", "M1"])
    events = r["time"][1:][np.diff(r["time"]) == 0]
    assert len(events) == 1 and abs(events[0] - 12.0) < 1e-4, events
    analytic = -0.1 * np.minimum(r["time"], 12.0)
    assert np.max(np.abs(r["integral1"] - analytic)) < 1e-6, np.max(np.abs(r["integral1"] - analytic))
    assert r["M1"][-1] == -2.0


def test_the_sampled_controller_in_model_exchange_equals_its_co_simulation_at_the_samples():
    """sampled = true in Model Exchange: time events every Ts, the PID memory advancing at the
    samples only and the measurement of the previous sample in the outputs (one sample of
    delay), as a co-simulation step of Ts does. Driven by the same measured signal, the commands
    at every sample instant agree to rounding (fmpy's co-simulation steps are differences of
    communication points, Ts within a few ulps)."""
    ts = 0.01
    t = np.linspace(0.0, 0.2, 41)
    signal = np.zeros(len(t), dtype=[("time", float), ("alpha1", float), ("omega1", float), ("alpha1_ref", float),
                                     ("alpha2_ref", float)])
    signal["time"], signal["alpha1"], signal["omega1"] = t, 0.3 * np.sin(20 * t), 6.0 * np.cos(20 * t)
    start = {"sampled": True, "mode": 3, "Ts": ts}
    out = ["M1", "M2", "U1", "U2", "integral1"]
    kw = dict(stop_time=0.2, output_interval=ts, input=signal, start_values=start, output=out)
    me = fmpy.simulate_fmu(fmu("Controller"), fmi_type="ModelExchange", **kw)
    cs = fmpy.simulate_fmu(fmu("Controller"), fmi_type="CoSimulation", **kw)
    saturated = 0
    for k in range(1, 21):
        i = np.flatnonzero(np.abs(me["time"] - k * ts) < 1e-9)[-1]
        j = np.flatnonzero(np.abs(cs["time"] - k * ts) < 1e-9)[-1]
        for name in out:
            assert abs(me[name][i] - cs[name][j]) < 1e-12, (k, name, me[name][i], cs[name][j])
        saturated += abs(cs["M1"][j]) == 20.0
    # Through the limit and back.
    assert 0 < saturated < 20
    # Held between the samples: at 1 ms, constant on every (k Ts, (k + 1) Ts).
    fine = fmpy.simulate_fmu(fmu("Controller"), fmi_type="ModelExchange", **dict(kw, output_interval=1e-3))
    for k in range(20):
        inside = (fine["time"] > k * ts + 1e-9) & (fine["time"] < (k + 1) * ts - 1e-9)
        assert inside.sum() >= 8 and len(set(fine["M1"][inside])) == 1, (k, fine["M1"][inside])


def test_fmi3_co_simulation_with_event_mode_returns_at_every_bounce():
    """FMI 3.0 Co-Simulation with eventModeUsed and earlyReturnAllowed (fmpy's use_event_mode,
    early_return_allowed): fmi3DoStep returns early at each bounce with eventHandlingNeeded, fmpy
    handles it in Event Mode (fmi3UpdateDiscreteStates) and steps on from there. The early returns
    are the analytic bounce times within 1e-9 s, and at the communication points the ball is where
    the run without event mode (events handled inside the step) puts it."""
    kw = dict(fmi_type="CoSimulation", output_interval=1e-2)
    r = simulate(fmu3("BouncingBall"), use_event_mode=True, early_return_allowed=True, **kw)
    inside = r["time"][np.abs(r["time"] / 1e-2 - np.round(r["time"] / 1e-2)) > 1e-6]
    returns = np.unique(inside)
    seq = [tb for tb, _ in bounces()]
    assert len(returns) == len(seq), (returns, seq)
    assert np.max(np.abs(returns - seq)) < 1e-9, np.max(np.abs(returns - seq))
    internal = simulate(fmu3("BouncingBall"), **kw)
    on_grid = np.abs(r["time"] / 1e-2 - np.round(r["time"] / 1e-2)) <= 1e-6
    assert on_grid.sum() == len(internal)
    assert np.max(np.abs(r["h"][on_grid] - internal["h"])) < 1e-12
    assert np.max(np.abs(r["v"][on_grid] - internal["v"])) < 1e-11
