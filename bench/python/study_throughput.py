"""Throughput of parameter studies: runs per second per core of the full loop (PendulumMotors.ssp,
controller -> two motors -> pendulum, 10 s at 1 ms) in the native SSP runner (rustfmu_runner,
in-process), the fmpy master (examples/cosim/master.py) and libcosim, side by side in one
process, next to the benchmark's bare native loop (composed-loop); then one Monte Carlo
robustness study on a Dask LocalCluster of 1 and 2 workers and on a `dask scheduler` +
`dask worker` started here by hand, with the rows compared (identical results), and a subset of
it on the fmpy master (the largest difference reported). The machine's load average is printed
with every measurement. Asserts nothing about time.

    .venv/bin/python bench/python/study_throughput.py [--runs 20 --fmpy-runs 3 --study-runs 2000]
    .venv/bin/python bench/python/study_throughput.py --quick
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "examples"))
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
FMU_DIR = TARGET / "fmu"
SSP = FMU_DIR / "PendulumMotors.ssp"
RECORD = ["pendulum.alpha1", "pendulum.alpha2"]


def load() -> str:
    return "load average %.2f %.2f %.2f" % os.getloadavg()


def per_run(fn, runs: int) -> tuple[float, float]:
    """Median and best CPU seconds of this thread per call of fn() over `runs` calls (after one warm-up)."""
    fn()
    times = []
    for _ in range(runs):
        c0 = time.thread_time()
        fn()
        times.append(time.thread_time() - c0)
    return float(np.median(times)), float(min(times))


def native(stop, step):
    import rustfmu_runner

    s = rustfmu_runner.System(str(SSP))
    return lambda: s.run(stop, step, record=RECORD)


def fmpy_master(stop, step):
    from cosim.master import Loop
    from cosim.systems import bind, read_ssp

    system = bind(read_ssp(SSP), {k: str(FMU_DIR / f"{k}.fmu") for k in ("Pendulum", "Controller", "DCMotor")})
    loop = Loop(system)
    n = int(round(stop / step))
    data = np.empty((n + 1, 2))
    ports = loop.port("pendulum", ("alpha1", "alpha2"))

    def observe(k, _t):
        data[k] = list(ports.get())
        return True

    return lambda: loop.run(stop, step, {}, observe)


def libcosim(stop, step):
    from cosim.ssp import simulate_libcosim

    return lambda: simulate_libcosim(str(SSP), stop, step, RECORD, {})


def bare_loop(stop, step) -> float:
    """The benchmark's bare native loop (composed-loop, the `full` topology): CPU s per run
    (initialization and the steps), from the CPU time of 21 runs minus that of 1 (loading the
    FMUs is not counted), as the other masters are measured."""
    import resource

    exe = TARGET / "release" / "composed-loop"
    if not exe.exists():
        subprocess.run(["cargo", "build", "--release", "-q", "-p", "rustfmu-bench", "--bin", "composed-loop"], cwd=ROOT, check=True)

    def cpu(repeat):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([str(exe), "--seconds", str(stop), "--step", str(step), "--repeat", str(repeat)], capture_output=True, text=True, check=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        return (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)

    return min((cpu(21) - cpu(1)) / 20 for _ in range(3))


def compare(a: list[dict], b: list[dict], what: str) -> float:
    """Asserts the same outcome columns; returns the largest numeric difference."""
    from pendulum_study import runner

    cols = [c for c in runner.RESULT_COLUMNS if c not in runner.BOOKKEEPING_COLUMNS and c != "error"]
    a = {r["run_id"]: r for r in a}
    b = {r["run_id"]: r for r in b}
    assert a.keys() == b.keys(), f"{what}: different runs"
    worst = 0.0
    for rid in a:
        for c in cols:
            x, y = a[rid][c], b[rid][c]
            if isinstance(x, float) or isinstance(y, float):
                x, y = float(x), float(y)
                if math.isnan(x) and math.isnan(y):
                    continue
                worst = max(worst, abs(x - y))
            elif str(x) != str(y):
                raise AssertionError(f"{what}: run {rid} {c}: {x!r} vs {y!r}")
    return worst


def read_rows(path) -> list[dict]:
    import pandas as pd

    df = pd.read_csv(path, keep_default_na=False, na_values=[""])
    return df.to_dict("records")


def hand_started_cluster(nworkers: int, tmp: str):
    """`dask scheduler` and `dask worker` processes, started as a user starts them."""
    dask = str(pathlib.Path(sys.executable).parent / "dask")
    sched_file = os.path.join(tmp, "scheduler.json")
    env = dict(os.environ, PYTHONPATH=str(ROOT / "examples"))
    sched = subprocess.Popen([dask, "scheduler", "--scheduler-file", sched_file, "--port", "0", "--dashboard-address", ":0"], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(300):
        if os.path.exists(sched_file):
            break
        time.sleep(0.1)
    worker = subprocess.Popen(
        [dask, "worker", "--scheduler-file", sched_file, "--nworkers", str(nworkers), "--nthreads", "1", "--dashboard-address", ":0"],
        env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    address = json.load(open(sched_file))["address"]
    from distributed import Client

    with Client(address) as c:
        c.wait_for_workers(nworkers, timeout=120)
    return address, (worker, sched)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--runs", type=int, default=20, help="native runs per measurement")
    p.add_argument("--fmpy-runs", type=int, default=3, help="fmpy and libcosim runs per measurement")
    p.add_argument("--study-runs", type=int, default=2000, help="runs of the Monte Carlo study on Dask")
    p.add_argument("--check-runs", type=int, default=20, help="runs of the study also done on the fmpy master")
    p.add_argument("--stop-time", type=float, default=10.0)
    p.add_argument("--step", type=float, default=1e-3)
    p.add_argument("--quick", action="store_true", help="1 s runs, few of them (CI: proves it runs)")
    p.add_argument("--json", help="write the numbers here")
    p.add_argument("--no-dask", action="store_true", help="only the runs per second per core")
    a = p.parse_args(argv)
    if a.quick:
        a.runs, a.fmpy_runs, a.study_runs, a.check_runs, a.stop_time = 3, 1, 8, 4, 1.0
    if not SSP.exists():
        p.error(f"{SSP} is missing: run `cargo run --release -p fmu-build` first")
    stop, step = a.stop_time, a.step
    print(f"full loop (PendulumMotors.ssp), {stop:g} s at {step:g} s, on {os.cpu_count()} cores; {load()}")
    result = {"stop_time": stop, "step": step, "cores": os.cpu_count(), "load_start": os.getloadavg()}
    bare = bare_loop(stop, step)
    print(f"  bare native loop (composed-loop) CPU per run: {bare * 1e3:8.2f} ms   ({load()})")
    result["bare_s"] = bare
    for name, make, runs in (("native runner", native, a.runs), ("fmpy master", fmpy_master, a.fmpy_runs), ("libcosim", libcosim, a.fmpy_runs)):
        med, best = per_run(make(stop, step), runs)
        print(f"  {name:14s} CPU per run: median {med * 1e3:8.2f} ms, best {best * 1e3:8.2f} ms = {1 / med:7.2f} runs/s per core, {med / bare:5.2f} x the bare loop   ({load()})")
        result[name] = {"median_s": med, "best_s": best, "runs_per_s_per_core": 1 / med}

    if a.no_dask:
        return 0
    from pendulum_study import runner, studies

    paths = {k: str(FMU_DIR / f"{k}.fmu") for k in ("Pendulum", "Controller", "DCMotor")}
    specs = studies.robustness(paths, (a.study_runs + 1) // 2, 0.2, 1, (1, 3), "motors", stop_time=stop, step=step)[: a.study_runs]
    print(f"Monte Carlo robustness study: {len(specs)} runs of {stop:g} s at {step:g} s, native runner")
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1, 2):
            out = pathlib.Path(tmp) / f"local-{n}.csv"
            l0 = load()
            rep = runner.run_study(specs, out, paths, n_workers=n, progress=False)
            print(f"  LocalCluster, {n} worker(s): {rep.runs_per_second:8.1f} runs/s, {rep.wall_time:6.1f} s ({rep.failed} failed; {l0} -> {load()})")
            result[f"local_{n}"] = {"runs_per_s": rep.runs_per_second, "wall_s": rep.wall_time}
            rows[f"LocalCluster {n}"] = read_rows(out)
        address, procs = hand_started_cluster(2, tmp)
        try:
            out = pathlib.Path(tmp) / "hand.csv"
            l0 = load()
            rep = runner.run_study(specs, out, paths, scheduler=address, progress=False)
            print(f"  dask scheduler + dask worker --nworkers 2 (by hand): {rep.runs_per_second:8.1f} runs/s, {rep.wall_time:6.1f} s ({rep.failed} failed; {l0} -> {load()})")
            result["hand_2"] = {"runs_per_s": rep.runs_per_second, "wall_s": rep.wall_time}
            rows["by hand"] = read_rows(out)
        finally:
            for proc in procs:
                proc.terminate()
                proc.wait(timeout=60)
    base = rows["LocalCluster 1"]
    for what, r in rows.items():
        d = compare(r, base, what)
        print(f"  {what}: rows identical to LocalCluster 1 (largest difference {d:g})")
    check = specs[: a.check_runs]
    d = compare(runner.run_sequential(check, paths, master="native"), runner.run_sequential(check, paths, master="fmpy"), "native vs fmpy")
    print(f"  native vs fmpy master on {len(check)} of the runs: largest difference {d:g}")
    result["native_vs_fmpy"] = d
    result["load_end"] = os.getloadavg()
    for n in (1, 2):
        est = 10_000 / result[f"local_{n}"]["runs_per_s"]
        print(f"  => 10,000 runs on {n} worker(s): about {est:.0f} s")
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
