"""Running a study: many independent closed-loop runs, on Dask or one after another.

A run is a plain dict (a *spec*): ``{"system", "stop_time", "step", "criteria", "start"}`` where
``start`` maps "component.variable" to a start value. Its id is a hash of the spec, so the same
run has the same id in every study that contains it.

Each finished run is appended as one CSV row as soon as its result arrives; a study that is
started again on the same file skips every run id already in it (an interrupted study resumes
where it stopped; a row cut short by the interruption is dropped and its run redone). Rows
carry a digest of the FMU files: a file written with other FMUs is refused, not resumed.

On Dask every run is one task. A worker plugin carries the FMU files to each worker, which
extracts them once into its local directory; each worker thread instantiates each FMU once and
every later run on it starts with fmi2Reset (`closed_loop.FmuSet`).
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import hashlib
import io
import json
import logging
import math
import os
import pathlib
import tempfile
import time
import zipfile

from distributed import Client, LocalCluster, as_completed, get_worker
from distributed.diagnostics.plugin import WorkerPlugin

from cosim.systems import ssp_path

from .closed_loop import SSP_SYSTEMS, Criteria, FmuSet, study_systems

PLUGIN_NAME = "pendulum-study-fmus"

#: Columns every row has, after the run's parameters.
RESULT_COLUMNS = [
    "status",
    "outcome",
    "stabilized",
    "settling_time",
    "peak_alpha1",
    "peak_alpha2",
    "peak_torque",
    "peak_voltage",
    "final_error",
    "t_end",
    "fmi_status",
    "fmi_function",
    "error",
    "elapsed",
    "cpu",
    "worker",
    "loop_id",
    "loop_runs",
    "fmus",
    "master",
]

#: Columns that describe where and how fast a run ran, not what it computed.
BOOKKEEPING_COLUMNS = ["elapsed", "cpu", "worker", "loop_id", "loop_runs", "fmus", "master"]


def fmu_digest(paths: dict[str, str]) -> str:
    """Identifies the FMU files a study ran on: 12 hex digits of a SHA-256 over them."""
    h = hashlib.sha256()
    for ident in sorted(paths):
        h.update(ident.encode() + b"\0" + pathlib.Path(paths[ident]).read_bytes())
    return h.hexdigest()[:12]


def make_spec(system: str, start: dict, stop_time: float, step: float, criteria: Criteria = Criteria()) -> dict:
    return {
        "system": system,
        "stop_time": float(stop_time),
        "step": float(step),
        "criteria": dataclasses.asdict(criteria),
        "start": dict(start),
    }


def run_id(spec: dict) -> str:
    """A stable id of a run: the first 16 hex digits of the SHA-256 of its canonical JSON."""
    text = json.dumps(spec, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def execute(spec: dict, fmus: FmuSet) -> dict:
    """Runs one spec on a pooled closed loop of `fmus`; returns its row (without `worker`)."""
    loop = fmus.checkout(spec["system"])
    try:
        result = loop.run(spec["start"], spec["stop_time"], spec["step"], Criteria(**spec["criteria"]))
    finally:
        fmus.checkin(loop)
    return {**result, "loop_id": loop.id, "loop_runs": loop.runs, "master": fmus.master}


class FmuPlugin(WorkerPlugin):
    """Carries the FMU files and the systems (read from the SSP files here, on the client) to
    every worker (also to workers that join later) and keeps, per worker, the extracted FMUs and
    the pool of instantiated closed loops."""

    name = PLUGIN_NAME

    def __init__(self, paths: dict[str, str], master: str = "native"):
        self.files = {ident: pathlib.Path(path).read_bytes() for ident, path in paths.items()}
        # The SSP files (the native runner runs them), written next to the FMUs on the worker.
        self.ssp_files = {name: ssp_path(name, paths["Pendulum"]).read_bytes() for name in SSP_SYSTEMS.values()}
        self.systems = study_systems(paths)
        self.master = master
        self.fmus: FmuSet | None = None

    def setup(self, worker):
        digest = hashlib.sha256(b"".join(self.files[k] for k in sorted(self.files))).hexdigest()[:12]
        workdir = pathlib.Path(worker.local_directory) / f"pendulum-study-{digest}"
        workdir.mkdir(parents=True, exist_ok=True)
        paths = {}
        for ident, data in self.files.items():
            path = workdir / f"{ident}.fmu"
            path.write_bytes(data)
            paths[ident] = str(path)
        for name, data in self.ssp_files.items():
            (workdir / f"{name}.ssp").write_bytes(data)
        self.fmus = FmuSet(paths, str(workdir), self.systems, master=self.master)

    def teardown(self, worker):
        if self.fmus is not None:
            self.fmus.close()


def _task(spec: dict) -> dict:
    worker = get_worker()
    row = execute(spec, worker.plugins[PLUGIN_NAME].fmus)
    row["worker"] = worker.name
    return row


def flatten(spec: dict, result: dict) -> dict:
    return {
        "run_id": run_id(spec),
        "system": spec["system"],
        "stop_time": spec["stop_time"],
        "step": spec["step"],
        **spec["start"],
        **result,
    }


def columns_of(specs: list[dict]) -> list[str]:
    params = sorted({k for s in specs for k in s["start"]})
    return ["run_id", "system", "stop_time", "step", *params, *RESULT_COLUMNS]


def _format(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)  # round-trips exactly
    return str(value)


class RowFile:
    """The study's CSV file: one row per finished run, appended and flushed as each arrives."""

    def __init__(self, path: str | os.PathLike, columns: list[str], fmus: str):
        self.path = pathlib.Path(path).resolve()
        self.columns = columns
        self.fmus = fmus
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.done: dict[str, str] = {}  # run id -> status
        if self.path.exists() and self.path.stat().st_size > 0:
            self._load()
        else:
            self.path.write_text(self._line(self.columns))

    def _line(self, values) -> str:
        out = io.StringIO()
        csv.writer(out, lineterminator="\n").writerow(values)
        return out.getvalue()

    def _load(self) -> None:
        data = self.path.read_bytes()
        if not data.endswith(b"\n"):
            # A row cut short by an interruption: drop it, its run is done again.
            data = data[: data.rfind(b"\n") + 1]
            self.path.write_bytes(data)
        reader = csv.reader(io.StringIO(data.decode()))
        header = next(reader)
        if header != self.columns:
            raise ValueError(
                f"{self.path} holds another study (its columns are {header}, this study's are "
                f"{self.columns}); give another output file"
            )
        for row in reader:
            if len(row) == len(header):
                record = dict(zip(header, row))
                if record["fmus"] != self.fmus:
                    raise ValueError(
                        f"{self.path} holds runs of other FMU files (digest {record['fmus']}, now "
                        f"{self.fmus}): its rows would not be this study's; give another output file"
                    )
                self.done[record["run_id"]] = record["status"]

    def append(self, row: dict) -> None:
        row = {**row, "fmus": self.fmus}
        with open(self.path, "a", newline="") as f:
            f.write(self._line([_format(row.get(c)) for c in self.columns]))
            f.flush()


@dataclasses.dataclass
class StudyReport:
    total: int
    skipped: int
    executed: int
    failed: int
    wall_time: float  # from the first submission to the last result, s
    cpu_time: float  # CPU time of the runs in the workers' threads, summed, s
    setup_time: float  # starting or connecting to the cluster, shipping the FMUs, s
    workers: int
    threads: int  # worker threads in all
    path: str

    @property
    def runs_per_second(self) -> float:
        return self.executed / self.wall_time if self.wall_time > 0 else math.nan

    @property
    def cpu_share(self) -> float:
        """Fraction of the wall time the worker threads spent computing runs: 1 = every
        thread had a core to itself the whole time."""
        return self.cpu_time / (self.wall_time * self.threads) if self.wall_time > 0 and self.threads else math.nan

    def __str__(self) -> str:
        return (
            f"{self.executed} runs executed ({self.failed} failed), {self.skipped} of {self.total} "
            f"already in {self.path}; {self.wall_time:.2f} s on {self.workers} worker(s) = "
            f"{self.runs_per_second:.2f} runs/s, {self.cpu_time / max(1, self.executed) * 1e3:.0f} ms CPU per run, "
            f"worker threads computing {100 * self.cpu_share:.0f} % of the time (cluster setup {self.setup_time:.2f} s)"
        )


def _package_zip(directory: str) -> str:
    """This package and the `cosim` package it uses (its systems) as a zip file, for workers of
    an existing cluster that do not have them."""
    pkg = pathlib.Path(__file__).resolve().parent
    path = pathlib.Path(directory) / f"{pkg.name}.zip"
    with zipfile.ZipFile(path, "w") as z:
        for d in (pkg, pkg.parent / "cosim"):
            for f in sorted(d.glob("*.py")):
                z.write(f, f"{d.name}/{f.name}")
    return str(path)


def unique_specs(specs: list[dict]) -> list[dict]:
    seen, out = set(), []
    for s in specs:
        i = run_id(s)
        if i not in seen:
            seen.add(i)
            out.append(s)
    return out


def run_study(
    specs: list[dict],
    out: str | os.PathLike,
    fmu_paths: dict[str, str],
    scheduler: str | None = None,
    n_workers: int = 2,
    threads_per_worker: int = 1,
    processes: bool = True,
    progress: bool = True,
    retry_failed: bool = False,
    master: str = "native",
) -> StudyReport:
    """Runs every spec not yet in `out` as one Dask task and appends its row to `out`.

    `scheduler`: address of an existing Dask scheduler ("tcp://host:8786"); None starts a
    LocalCluster of `n_workers` workers with `threads_per_worker` threads (processes or threads).
    `master`: "native" (the SSP runner in-process, the default), "isolated" (the same, each FMU
    in a child process) or "fmpy" (the reference).
    """
    from tqdm import tqdm

    specs = unique_specs(specs)
    rows = RowFile(out, columns_of(specs), fmu_digest(fmu_paths))
    keep = {"ok"} if retry_failed else {"ok", "failed"}
    todo = [s for s in specs if rows.done.get(run_id(s)) not in keep]
    report = StudyReport(len(specs), len(specs) - len(todo), 0, 0, 0.0, 0.0, 0.0, 0, 0, str(rows.path))
    if not todo:
        return report
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        if scheduler is None:
            cluster = stack.enter_context(
                LocalCluster(
                    n_workers=n_workers,
                    threads_per_worker=threads_per_worker,
                    processes=processes,
                    dashboard_address=":0",  # any free port: several studies may run at once
                    silence_logs=logging.CRITICAL,  # workers' heartbeat complaints at shutdown
                )
            )
            client = stack.enter_context(Client(cluster))
        else:
            client = stack.enter_context(Client(scheduler))
            # The workers of an existing cluster may not have this package: send it.
            tmp = stack.enter_context(tempfile.TemporaryDirectory())
            client.upload_file(_package_zip(tmp))
        client.register_plugin(FmuPlugin(fmu_paths, master))
        workers = client.scheduler_info()["workers"].values()
        report.workers, report.threads = len(workers), sum(w["nthreads"] for w in workers)
        report.setup_time = time.perf_counter() - t0
        t1 = time.perf_counter()
        futures = client.map(_task, todo, key=[f"run-{run_id(s)}" for s in todo], pure=False)
        by_key = {f.key: s for f, s in zip(futures, todo)}
        bar = stack.enter_context(tqdm(total=len(todo), unit="run", disable=not progress, smoothing=0.1))
        try:
            for future in as_completed(futures):
                spec = by_key[future.key]
                try:
                    result = future.result()
                except Exception as e:  # the worker died (e.g. a crash in native code)
                    result = {"status": "failed", "outcome": "failed", "stabilized": False, "error": f"{type(e).__name__}: {e}"}
                rows.append(flatten(spec, result))
                report.executed += 1
                report.failed += result["status"] == "failed"
                report.cpu_time += result.get("cpu", 0.0)
                bar.update()
        finally:
            report.wall_time = time.perf_counter() - t1
            client.cancel(futures)
    return report


def run_sequential(specs: list[dict], fmu_paths: dict[str, str], fresh: bool = False, out=None, master: str = "native") -> list[dict]:
    """The same runs one after another in this process, without Dask. `fresh`: a new instance
    of every FMU for every run (no fmi2Reset), the reference the pooled runs are checked against."""
    specs = unique_specs(specs)
    rows = RowFile(out, columns_of(specs), fmu_digest(fmu_paths)) if out is not None else None
    result = []
    fmus = FmuSet(fmu_paths, master=master)
    try:
        for spec in specs:
            if fresh:
                loop = fmus.checkout(spec["system"])  # pool is empty: a new loop
                try:
                    row = loop.run(spec["start"], spec["stop_time"], spec["step"], Criteria(**spec["criteria"]))
                    row = {**row, "loop_id": loop.id, "loop_runs": loop.runs, "master": master}
                finally:
                    loop.close()
            else:
                row = execute(spec, fmus)
            row = flatten(spec, {**row, "worker": "local"})
            result.append(row)
            if rows is not None:
                rows.append(row)
    finally:
        fmus.close()
    return result
