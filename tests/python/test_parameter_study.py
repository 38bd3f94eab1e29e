"""The parameter-study runner (examples/pendulum_study): Dask gives the same rows as runs done
one after another; fmi2Reset between runs gives the same rows as fresh instances; a failed run is
recorded with its reason; an interrupted study resumes without redoing finished runs."""

import math
import pathlib
import sys

import pandas as pd
import pytest
from conftest import ROOT, fmu
from distributed import LocalCluster

sys.path.insert(0, str(ROOT / "examples"))
from pendulum_study import plots, runner, studies  # noqa: E402

STOP, STEP = 3.0, 0.01  # short horizon, 10 ms communication steps: each run takes milliseconds

#: A negative mass: the Pendulum FMU refuses it in fmi2SetReal.
BAD_MASS = {"controller.mode": 1, "pendulum.alpha1_0": 0.1, "pendulum.m1": -0.5}
#: Both links started near horizontal on the same side: the LQR cannot catch them.
FALLS = {"controller.mode": 1, "pendulum.alpha1_0": 1.4, "pendulum.alpha2_0": 1.4}
#: The PID settles this one in about 4 s: not within a 3 s horizon.
SLOW = {"controller.mode": 2, "pendulum.alpha1_0": 0.0, "pendulum.alpha2_0": 0.5}


def small_study() -> list[dict]:
    """20 runs: a 3 x 3 grid of initial angles for LQR and PID (18), the failing and the falling
    run in the middle, and two runs of the four-FMU system with a perturbed plant."""
    grid = studies.region_of_attraction(modes=(1, 2), n=3, amax=0.2, stop_time=STOP, step=STEP)
    odd = [runner.make_spec("torque", s, STOP, STEP) for s in (BAD_MASS, FALLS, SLOW)]
    motors = [
        runner.make_spec("motors", {"controller.mode": 1, "pendulum.alpha1_0": 0.1, "pendulum.alpha2_0": -0.05, "pendulum.m2": m2, "motor1.R": 2.0}, STOP, STEP)
        for m2 in (0.45, 0.55)
    ]
    return grid[:9] + odd + grid[9:15] + motors


def paths() -> dict:
    return {name: fmu(name) for name in ("Pendulum", "Controller", "DCMotor")}


COMPARED = [c for c in runner.RESULT_COLUMNS if c not in runner.BOOKKEEPING_COLUMNS]


def assert_same_results(got: pd.DataFrame, expected: pd.DataFrame, what: str) -> None:
    got = got.set_index("run_id").sort_index()
    expected = expected.set_index("run_id").sort_index()
    assert list(got.index) == list(expected.index), f"{what}: runs {list(got.index)} != {list(expected.index)}"
    for c in COMPARED:
        for rid, a, b in zip(got.index, got[c], expected[c]):
            same = a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))
            assert same, f"{what}: run {rid} column {c}: {a!r}, expected {b!r} (as run one after another without Dask)"


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> pathlib.Path:
    """The small study run one after another in this process, a fresh instance of every FMU
    for every run (no fmi2Reset)."""
    out = tmp_path_factory.mktemp("study") / "sequential.csv"
    runner.run_sequential(small_study(), paths(), fresh=True, out=out)
    return out


@pytest.fixture(scope="module")
def dask_run(tmp_path_factory):
    """The small study on a LocalCluster of two worker processes, one thread each."""
    out = tmp_path_factory.mktemp("study") / "dask.csv"
    report = runner.run_study(small_study(), out, paths(), n_workers=2, threads_per_worker=1, progress=False)
    return report, out


def test_study_on_local_cluster_gives_the_rows_of_sequential_runs(dask_run, reference):
    report, out = dask_run
    assert (report.executed, report.skipped, report.workers) == (len(small_study()), 0, 2), str(report)
    assert_same_results(pd.read_csv(out), pd.read_csv(reference), "Dask LocalCluster")


def test_workers_instantiate_once_and_reset_between_runs(dask_run):
    _, out = dask_run
    df = pd.read_csv(out)
    for (worker, system), d in df.groupby(["worker", "system"]):
        loops = d["loop_id"].unique()
        assert len(loops) == 1, f"worker {worker} instantiated {len(loops)} {system} loops, expected 1 (one thread)"
        assert sorted(d["loop_runs"]) == list(range(1, len(d) + 1)), f"worker {worker}: runs per instance {sorted(d['loop_runs'])}"
    assert df["loop_runs"].max() > 1, "no worker reused its FMU instances"


def test_reset_between_runs_gives_the_rows_of_fresh_instances(reference, tmp_path):
    # One pooled loop per system runs all 20 in order, including a failed run and a fall.
    rows = runner.run_sequential(small_study(), paths(), fresh=False, out=tmp_path / "pooled.csv")
    assert max(r["loop_runs"] for r in rows) > 10
    assert_same_results(pd.read_csv(tmp_path / "pooled.csv"), pd.read_csv(reference), "pooled with fmi2Reset")


def test_failed_run_is_recorded_with_its_reason_and_the_study_goes_on(dask_run):
    _, out = dask_run
    df = pd.read_csv(out).set_index("run_id")
    bad = df.loc[runner.run_id(runner.make_spec("torque", BAD_MASS, STOP, STEP))]
    assert bad["status"] == "failed" and not bad["stabilized"], bad.to_dict()
    assert bad["fmi_status"] == "Error" and bad["fmi_function"] == "fmi2SetReal", bad.to_dict()
    assert "-0.5 for 'm1' (vr 20) is outside (0, inf)" in bad["error"], f"error text: {bad['error']!r}"
    fell = df.loc[runner.run_id(runner.make_spec("torque", FALLS, STOP, STEP))]
    assert (fell["status"], fell["outcome"]) == ("ok", "fell") and fell["t_end"] < STOP, fell.to_dict()
    slow = df.loc[runner.run_id(runner.make_spec("torque", SLOW, STOP, STEP))]
    assert (slow["status"], slow["outcome"]) == ("ok", "not_stabilized") and slow["t_end"] == STOP, slow.to_dict()
    others = df.drop(index=[bad.name])
    assert (others["status"] == "ok").all(), others[others["status"] != "ok"]["error"].to_dict()
    assert others["stabilized"].sum() >= 10, f"only {others['stabilized'].sum()} of {len(others)} runs stabilized"


def test_resume_skips_finished_runs_and_redoes_a_row_cut_short(reference, tmp_path):
    specs = small_study()
    lines = reference.read_text().splitlines(keepends=True)
    finished = 8
    # An interrupted study: the header, 8 finished rows, and the 9th cut in the middle.
    out = tmp_path / "resumed.csv"
    out.write_text("".join(lines[: 1 + finished]) + lines[1 + finished][:40])
    # On an existing cluster given by its address, as `--scheduler tcp://...` does.
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        report = runner.run_study(specs, out, paths(), scheduler=cluster.scheduler_address, progress=False)
    assert (report.skipped, report.executed) == (finished, len(specs) - finished), str(report)
    df = pd.read_csv(out)
    assert df["run_id"].is_unique and len(df) == len(specs), f"{len(df)} rows, {df['run_id'].nunique()} ids"
    ran_on_cluster = int((df["worker"] != "local").sum())  # the reference rows ran "local"
    assert ran_on_cluster == len(specs) - finished, f"{ran_on_cluster} runs executed on the cluster"
    per_loop = df[df["worker"] != "local"].groupby("system")["loop_runs"].max()
    assert per_loop.sum() == len(specs) - finished, f"runs per pooled loop of the one worker: {per_loop.to_dict()}"
    assert_same_results(df, pd.read_csv(reference), "resumed")
    again = runner.run_study(specs, out, paths(), scheduler="tcp://127.0.0.1:9", progress=False)  # no cluster needed
    assert (again.skipped, again.executed) == (len(specs), 0), str(again)


def test_study_file_of_another_study_is_refused(reference):
    other = [runner.make_spec("torque", {"controller.mode": 1, "pendulum.l2": 0.9}, STOP, STEP)]
    with pytest.raises(ValueError, match="holds another study"):
        runner.run_study(other, reference, paths(), progress=False)


def test_study_file_of_other_fmus_is_refused(reference, tmp_path):
    changed = dict(paths())
    changed["Pendulum"] = str(tmp_path / "Pendulum.fmu")
    pathlib.Path(changed["Pendulum"]).write_bytes(pathlib.Path(paths()["Pendulum"]).read_bytes() + b"\0")
    with pytest.raises(ValueError, match="other FMU files"):
        runner.run_study(small_study(), reference, changed, progress=False)


def test_pictures_are_written(dask_run, tmp_path):
    _, out = dask_run
    df = pd.read_csv(out)
    torque = df[df["system"] == "torque"].dropna(subset=["pendulum.alpha2_0"])
    plots.region_of_attraction(torque, tmp_path / "roa.png")
    plots.robustness(df[df["system"] == "motors"], tmp_path / "robust.png", 0.2)
    for name in ("roa.png", "robust.png"):
        data = (tmp_path / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000, f"{name}: {len(data)} bytes"


@pytest.mark.parametrize("system", ["torque", "motors"])
def test_study_runs_match_the_composition_master_loop(system):
    """The study's closed loop (instances kept, fmi2Reset) against examples/cosim's master loop
    (fresh instances): same systems, same call order, so the same trajectory to the last bit."""
    from cosim import plant_and_controller, plant_motors_controller, simulate

    from pendulum_study.closed_loop import FmuSet

    p = paths()
    if system == "torque":
        composed = plant_and_controller(p["Pendulum"], p["Controller"], 0.1, -0.05, mode=2)
    else:
        composed = plant_motors_controller(p["Pendulum"], p["Controller"], p["DCMotor"], 0.1, -0.05, mode=3)
    stop, step = 1.0, 1e-3
    traj = simulate(composed, stop, step, {"pendulum": ["alpha1", "alpha2"]})
    fmus = FmuSet(p)
    try:
        loop = fmus.checkout(system)
        start = {"controller.mode": 2 if system == "torque" else 3, "pendulum.alpha1_0": 0.1, "pendulum.alpha2_0": -0.05}
        loop.run({**start, "pendulum.m1": 0.6}, stop, step)  # a different run first: reset must undo it
        row = loop.run(start, stop, step)
    finally:
        fmus.close()
    a1, a2 = traj["pendulum.alpha1"], traj["pendulum.alpha2"]
    assert row["peak_alpha1"] == abs(a1).max() and row["peak_alpha2"] == abs(a2).max(), (row, abs(a1).max(), abs(a2).max())
    assert row["final_error"] == math.hypot(a1[-1], a2[-1]), (row["final_error"], math.hypot(a1[-1], a2[-1]))


def test_each_loop_keeps_its_own_fmu_messages_when_loops_are_pooled():
    # fmpy's native logger proxy sends every instance's messages to the Python logger registered
    # last; the study routes them by componentEnvironment instead. Here the torque loop is built
    # first, the motors loop after it, then the torque loop's controller refuses a value: its
    # message must reach the torque run's error text, and no motors run's.
    specs = [
        runner.make_spec("torque", {"pendulum.alpha1_0": 0.05}, 0.2, STEP),
        runner.make_spec("motors", {"pendulum.alpha1_0": 0.05}, 0.2, STEP),
        runner.make_spec("torque", {"controller.mode": 7}, 0.2, STEP),
        runner.make_spec("motors", {"pendulum.m1": -1.0}, 0.2, STEP),
    ]
    rows = runner.run_sequential(specs, paths(), fresh=False)
    assert [r["status"] for r in rows] == ["ok", "ok", "failed", "failed"], [r["error"] for r in rows]
    assert "[controller: Error]" in rows[2]["error"] and "'mode'" in rows[2]["error"], rows[2]["error"]
    assert "[pendulum: Error]" in rows[3]["error"] and "'m1'" in rows[3]["error"], rows[3]["error"]
    assert "'mode'" not in rows[3]["error"], rows[3]["error"]
