"""Issue 52, item 5: running FMI 3.0 FMUs with clocks or structural parameters from Python. fmpy's
`simulate_fmu` does neither (pinned first, the trap a user falls into); python/rustfmu_loops.py,
the importer loops on fmpy's classes that docs/python.md documents, does both, on this project's
FMUs and on the C Reference-FMUs' (v0.0.41 in ../shared/independent): the ticks where each clock's
kind puts them, the counters and outputs the models define at each tick, the state-space outputs
of the sizes the structural parameters give, equal to the exact solution of x' = Ax + Bu."""

import pathlib
import re
import sys

import fmpy
import numpy as np
import pytest
import scipy.linalg

from conftest import ROOT, fmu3

sys.path.insert(0, str(ROOT / "python"))
import rustfmu_loops  # noqa: E402
from rustfmu_loops import simulate_clocked, simulate_configured  # noqa: E402

THEIRS = ROOT.parent / "shared" / "independent" / "reference-fmus" / "3.0"


def theirs(name):
    path = THEIRS / f"{name}.fmu"
    if not path.exists():
        pytest.fail(f"{path} is missing (the C Reference-FMUs v0.0.41 of shared/independent)")
    return str(path)


# -- the trap: fmpy's simulate_fmu ---------------------------------------------------------------


def test_fmpy_simulate_fmu_runs_a_clocked_model_exchange_fmu_without_a_tick():
    """What the user met: the run completes, and no clock ever ticked (inClock3Ticks, an
    unclocked counter, stays 0; the recipe below counts its tick at 4.5 s)."""
    r = fmpy.simulate_fmu(fmu3("Clocks"), fmi_type="ModelExchange", stop_time=10.0, output=["inClock3Ticks"])
    assert r["time"][-1] == 10.0 and set(r["inClock3Ticks"]) == {0}
    ours = simulate_clocked(fmu3("Clocks"), 10.0, interface="ModelExchange", output=["inClock3Ticks"])
    assert ours["inClock3Ticks"][-1] == 1


def test_fmpy_simulate_fmu_refuses_clocks_in_co_simulation_and_structural_parameters():
    with pytest.raises(Exception, match="Failed to instantiate"):
        fmpy.simulate_fmu(fmu3("SampledController"), fmi_type="CoSimulation", stop_time=0.1)
    for path in (fmu3("StateSpace"), theirs("StateSpace")):
        # Set in Instantiated, where FMI 3.0 refuses a structural parameter.
        with pytest.raises(Exception, match="fmi3SetUInt64 failed"):
            fmpy.simulate_fmu(path, start_values={"n": 2}, stop_time=1.0)


# -- clocks ----------------------------------------------------------------------------------------

STOP = 10.0
INCLOCK2 = [0.0, 1.0, 8.0, 9.0]


def input2(t):
    return int(t) + 1


def replay(ticks, grouped):
    """The Clocks model's definition, replayed over the input clocks' ticks: every tick adds one
    to totalInClockTicks (one Event Mode round of model exchange and co-simulation adds all the
    clocks ticking in it; scheduled execution activates each clock alone), and outClock ticks
    where a round or activation brings the total to a multiple of 5."""
    events = sorted((t, name) for name in ("inClock1", "inClock2", "inClock3") for t in ticks[name])
    rounds = {}
    for t, name in events:
        rounds.setdefault(t if grouped else (t, name), []).append(name)
    total, out = 0, []
    for key, names in rounds.items():
        total += len(names)
        if total % 5 == 0:
            out.append(key if grouped else key[0])
    return total, out


CLOCKS = [
    ("ours", "ModelExchange", 4.5),
    ("ours", "CoSimulation", 4.5),
    ("ours", "ScheduledExecution", 4.5),
    # The Reference-FMUs' Clocks is scheduled execution only; its partition 1 gives inClock3 the
    # countdown interval 0 at t = 4 (ours gives 0.5: docs/scheduled-execution.md).
    ("theirs", "ScheduledExecution", 4.0),
]


@pytest.mark.parametrize("who,interface,inclock3_at", CLOCKS, ids=[f"{w}-{i}" for w, i, _ in CLOCKS])
def test_every_kind_of_input_clock_ticks_and_the_counters_are_the_models(who, interface, inclock3_at):
    path = fmu3("Clocks") if who == "ours" else theirs("Clocks")
    r = simulate_clocked(path, STOP, interface=interface, triggers={"inClock2": INCLOCK2}, inputs={"input2": input2})
    # inClock1: constant, 1 s from 0: floor(STOP / 1) + 1 ticks, 0 to 10 inclusive.
    assert r.ticks["inClock1"] == [float(k) for k in range(int(STOP) + 1)]
    assert r.ticks["inClock2"] == INCLOCK2
    assert r.ticks["inClock3"] == [inclock3_at]
    total, out = replay(r.ticks, grouped=interface != "ScheduledExecution")
    assert r.ticks["outClock"] == out == [2.0, 6.0, 9.0], r.ticks
    last = r.rows[-1]
    assert (last["time"], last["inClock1Ticks"], last["inClock2Ticks"], last["inClock3Ticks"]) == (STOP, 11, 4, 1)
    assert last["totalInClockTicks"] == total == 16
    # result2 adds input2 at each tick of inClock2; output3 is 1000 from inClock3's tick on.
    assert last["result2"] == sum(input2(t) for t in INCLOCK2) == 22
    assert last["output3"] == 1000
    # inClock1Ticks, read at each tick of inClock1 (its clock), counts them.
    at = {float(t): int(n) for t, n in zip(r["time"], r["inClock1Ticks"])}
    assert all(at[float(k)] == k + 1 for k in range(int(STOP) + 1)), at
    # output3 before inClock3's tick: its start (0), held.
    assert set(r["output3"][r["time"] < inclock3_at]) == {0}


def measurement(t):
    """alpha1, omega1, alpha2, omega2: a measurement that changes between the ticks."""
    return np.array([0.1 * np.sin(2 * t), 0.2 * np.cos(2 * t), -0.05 * np.sin(3 * t), 0.15 * np.cos(3 * t)])


@pytest.mark.parametrize("interface", ["ModelExchange", "CoSimulation"])
def test_the_sampled_controller_commands_the_lqr_of_the_previous_ticks_measurement(interface):
    """SampledController (LQR mode): at its k-th tick of `sample` (every Ts = 10 ms) it outputs
    M = -K x((k - 1) Ts), the measurement of the tick before (at tick 0: of tick 0)."""
    names = ["alpha1", "omega1", "alpha2", "omega2"]
    inputs = {n: (lambda i: lambda t: measurement(t)[i])(i) for i, n in enumerate(names)}
    stop, ts = 0.5, 0.01
    r = simulate_clocked(fmu3("SampledController"), stop, interface=interface, inputs=inputs,
                         output=["M1", "M2", "K"])
    ticks = r.ticks["sample"]
    assert len(ticks) == int(round(stop / ts)) + 1 and np.allclose(ticks, np.arange(len(ticks)) * ts, rtol=0, atol=1e-15)
    K = r["K"][0]
    assert K.shape == (2, 4)
    M = np.stack([r["M1"], r["M2"]], axis=1)
    want = np.array([-K @ measurement(max(k - 1, 0) * ts) for k in range(len(ticks))])
    assert np.allclose(M, want, rtol=1e-13, atol=1e-15), np.max(np.abs(M - want))


def test_a_triggered_time_on_a_clock_that_is_not_triggered_is_refused_with_the_clocks_that_are():
    with pytest.raises(ValueError, match=r"'inClock1' is no triggered input clock .*\(those are: inClock2\)"):
        simulate_clocked(fmu3("Clocks"), 1.0, triggers={"inClock1": [0.5]})


# -- structural parameters ------------------------------------------------------------------------


def system(m, n, r, seed):
    rng = np.random.default_rng(seed)
    return dict(
        A=rng.normal(size=(n, n)) - 2.0 * np.eye(n),
        B=rng.normal(size=(n, m)),
        C=rng.normal(size=(r, n)),
        D=rng.normal(size=(r, m)),
        x0=rng.normal(size=n),
    ), rng.normal(size=m)


def exact(s, u, t):
    """y(t) for a constant u: x(t) = e^{At} x0 + (integral of e^{As} ds over [0, t]) B u."""
    A, B, C, D, x0 = s["A"], s["B"], s["C"], s["D"], s["x0"]
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    E = scipy.linalg.expm(M * t)
    return C @ (E[:n, :n] @ x0 + E[:n, n:] @ u) + D @ u


SIZES = [(2, 4, 2), (1, 2, 3), (3, 5, 1)]


@pytest.mark.parametrize("interface", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("m,n,r", SIZES)
def test_our_state_space_with_new_sizes_follows_the_exact_solution(interface, m, n, r):
    s, u = system(m, n, r, seed=100 * m + 10 * n + r)
    res = simulate_configured(fmu3("StateSpace"), dict(m=m, n=n, r=r), 2.0, interface=interface,
                              start_values=s, inputs={"u": u}, output=["y", "x"], output_interval=0.25,
                              relative_tolerance=1e-10)
    assert list(res["time"]) == [0.25 * k for k in range(9)]
    assert res["y"].shape == (9, r) and res["x"].shape == (9, n)
    want = np.array([exact(s, u, t) for t in res["time"]])
    assert np.max(np.abs(res["y"] - want)) < 1e-7 * max(1.0, np.max(np.abs(want)))


def test_the_reference_fmus_state_space_at_its_own_sizes_follows_the_exact_solution():
    """Their StateSpace (v0.0.41) at the description's sizes (m = n = r = 3; no Configuration
    Mode): x starts at 0 whatever x0 (their model), model exchange integrated here to the exact
    solution; their co-simulation is forward Euler at 1 ms (their FIXED_SOLVER_STEP), equal to
    that recursion."""
    s, u = system(3, 3, 3, seed=5)
    s["x0"] = np.zeros(3)
    me = simulate_configured(theirs("StateSpace"), {}, 1.0, interface="ModelExchange", start_values=s,
                             inputs={"u": u}, output=["y"], output_interval=0.25, relative_tolerance=1e-10)
    want = np.array([exact(s, u, t) for t in me["time"]])
    assert me["y"].shape == (5, 3) and np.max(np.abs(me["y"] - want)) < 1e-7 * np.max(np.abs(want))
    cs = simulate_configured(theirs("StateSpace"), {}, 1.0, interface="CoSimulation", start_values=s,
                             inputs={"u": u}, output=["y"], output_interval=0.25)
    x, h, euler = np.zeros(3), 1e-3, {}
    for k in range(1001):
        if k % 250 == 0:
            euler[round(k * h, 9)] = s["C"] @ x + s["D"] @ u
        x = x + h * (s["A"] @ x + s["B"] @ u)
    assert np.allclose(cs["y"], [euler[round(t, 9)] for t in cs["time"]], rtol=1e-10, atol=1e-12)
    assert np.max(np.abs(cs["y"] - want)) < 1e-2 * np.max(np.abs(want))  # Euler at 1 ms


def test_the_reference_fmus_state_space_refuses_its_structural_parameters_and_the_error_quotes_it():
    """Their v0.0.41 fmi3SetUInt64 takes the value before checking nValues, so it refuses every
    structural parameter (fixed upstream since). The recipe's error names the parameter and
    quotes the FMU; when shared/independent gets a fixed build, this test fails: then test the
    configured sizes on theirs as on ours."""
    with pytest.raises(RuntimeError) as e:
        simulate_configured(theirs("StateSpace"), dict(n=2), 1.0)
    assert "setting structural parameter 'n' = 2 in Configuration Mode" in str(e.value)
    assert "the FMU said: Expected nValues >= 2 but was 1" in str(e.value), str(e.value)


def test_an_array_start_value_of_the_descriptions_size_is_refused_with_the_configured_size():
    s, u = system(3, 3, 3, seed=1)
    with pytest.raises(RuntimeError, match=r"'A' has 2 x 2 = 4 element\(s\) \(n = 2\); 9 value\(s\) were given"):
        simulate_configured(fmu3("StateSpace"), dict(n=2), 1.0, start_values={"A": s["A"]})
    with pytest.raises(ValueError, match="'A' is a parameter, not a structural parameter"):
        simulate_configured(fmu3("StateSpace"), dict(A=2), 1.0)


# -- the docs ---------------------------------------------------------------------------------------


def test_the_recipes_in_docs_python_md_run_as_written(monkeypatch):
    """Every ```python block of docs/python.md, run in order from the repository's root (they
    assert what they show)."""
    text = (ROOT / "docs" / "python.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 2
    monkeypatch.chdir(ROOT)
    scope = {}
    for block in blocks:
        exec(compile(block, "docs/python.md", "exec"), scope)  # noqa: S102


def test_the_module_needs_fmpy_and_numpy_only():
    imports = set(re.findall(r"^(?:from|import) (\w+)", pathlib.Path(rustfmu_loops.__file__).read_text(), flags=re.M))
    stdlib = {"__future__", "ctypes", "heapq", "math", "xml", "collections", "dataclasses", "pathlib", "typing"}
    assert imports - stdlib == {"fmpy", "numpy"}, imports
