"""`rustfmu-runner run --record-intermediate-values`: the values FMI 3.0 co-simulation components
give inside their steps (FMI 3.0.2, Intermediate Update Mode: the intermediateUpdate callback,
intermediateVariableGetAllowed), as rows of their own, against fmusim's option of the same name
(../shared/independent/bin/fmusim, nobody here wrote it) on the C Reference BouncingBall."""

import numpy as np
import pytest
from test_runner import cli
from test_runner_fmi3_types import FMUSIM, REF, fmusim, need, ours, runner, write_ssp

STOP, STEP = 1.0, 0.1


def on_grid(t):
    k = np.round(np.asarray(t) / STEP)
    return np.abs(np.asarray(t) - k * STEP) <= 1e-9


def ball_ssp(tmp_path, *more):
    return write_ssp(tmp_path / "Ball.ssp", [("ball", need(REF / "BouncingBall.fmu")), *more])


def test_the_reference_bouncing_balls_intermediate_values_are_fmusims(tmp_path):
    """The runner's rows between the communication points are fmusim's, time for time and value
    for value (fmusim prints 16 significant digits: within 1e-15); the points themselves too."""
    need(FMUSIM)
    got = runner(tmp_path, ball_ssp(tmp_path), STOP, STEP, "--record", "ball.h", "--record", "ball.v",
                 "--record-intermediate-values")
    want = fmusim(tmp_path, need(REF / "BouncingBall.fmu"), STOP, STEP, "--record-intermediate-values",
                  "--output-variable", "h", "--output-variable", "v")
    t, wt = np.asarray(got["time"]), np.asarray(want["time"])
    inside, w_inside = ~on_grid(t), ~on_grid(wt)
    # The Reference BouncingBall calls back at every internal step (1 ms): 9 a step of 0.1 s.
    assert inside.sum() >= 80, inside.sum()
    assert np.all(np.diff(t) > 0), "the rows are in time order"
    assert len(t[inside]) == len(wt[w_inside]) and np.allclose(t[inside], wt[w_inside], rtol=0, atol=1e-12)
    for v in ("h", "v"):
        assert np.allclose(got[f"ball.{v}"][inside], want[v][w_inside], rtol=1e-15, atol=1e-15), v
    # The communication points: the runner's row each, fmusim's last row at each time.
    assert np.allclose(t[~inside], np.arange(0, 11) * STEP, atol=1e-12)
    last = {round(x / STEP): i for i, x in enumerate(wt) if on_grid(x)}
    for v in ("h", "v"):
        assert np.allclose(got[f"ball.{v}"][~inside], [want[v][last[k]] for k in range(11)], rtol=1e-15, atol=1e-15)


def test_without_the_option_only_the_communication_points(tmp_path):
    got = runner(tmp_path, ball_ssp(tmp_path), STOP, STEP, "--record", "ball.h")
    assert len(got["time"]) == 11


def test_in_a_system_each_component_gives_its_own_rows_and_says_what_it_cannot(tmp_path):
    """Two balls, the second dropped from 0.5 m, and our Dahlquist (it provides intermediate
    update but declares no variable intermediateUpdate="true"): the balls' rows between the
    points each carry that ball's values (NaN in the other columns), the Dahlquist's x only at the
    points, and the runner says why for x and for the parameter g."""
    ssp = ball_ssp(tmp_path, ("b", need(REF / "BouncingBall.fmu")), ("d", ours("Dahlquist")))
    out = tmp_path / "out.csv"
    r = cli("run", ssp, "--stop-time", STOP, "--step", STEP, "--no-progress", "--output", out,
            "--record", "ball.h", "--record", "b.h", "--record", "d.x", "--record", "ball.g",
            "--set", "b.h=0.5", "--record-intermediate-values")
    assert r.returncode == 0, r.stderr
    assert "d.x: not a Float64 scalar with intermediateUpdate=\"true\"" in r.stderr, r.stderr
    assert "ball.g: not a Float64 scalar with intermediateUpdate=\"true\"" in r.stderr, r.stderr
    from test_runner_fmi3_types import read_csv
    got = read_csv(out)
    t = np.asarray(got["time"])
    inside = ~on_grid(t)
    a = inside & ~np.isnan(got["ball.h"])
    b = inside & ~np.isnan(got["b.h"])
    assert a.sum() >= 80 and b.sum() >= 80
    assert not np.any(a & b), "a row between the points is one component's"
    assert np.all(np.isnan(got["d.x"][inside])) and np.all(np.isnan(got["ball.g"][inside]))
    assert not np.any(np.isnan(got["d.x"][~inside]))
    assert np.all(np.diff(t) >= 0)
    # Each ball alone gives the same values (a system changes none).
    alone = runner(tmp_path, ball_ssp(tmp_path), STOP, STEP, "--record", "ball.h", "--record-intermediate-values")
    ta = np.asarray(alone["time"])
    assert np.array_equal(t[a], ta[~on_grid(ta)]) and np.array_equal(got["ball.h"][a], alone["ball.h"][~on_grid(ta)])


@pytest.mark.parametrize("extra, why", [(("--isolate",), "not with --isolate"),
                                        (("--tolerance", "1e-4"), "not with --tolerance")])
def test_refused_where_it_cannot_be_done(tmp_path, extra, why):
    r = cli("run", ball_ssp(tmp_path), "--stop-time", STOP, "--step", STEP, "--no-progress", "--record", "ball.h",
            "--record-intermediate-values", *extra)
    assert r.returncode != 0 and why in r.stderr, r.stderr
