"""One closed-loop co-simulation of the project's FMUs through fmpy, with instances kept alive.

A `ClosedLoop` instantiates its FMUs once (fmi2Instantiate) and runs any number of experiments
on them, each after the first starting with fmi2Reset: every variable is back at its start
value, then the experiment's parameters and initial state are set, the FMUs are initialized and
stepped.

Two systems, the project's composed systems as `fmu-build` writes them to SSP files (read by
`cosim.systems`, the same description the composition demo and its master loop use):

- ``torque`` = PendulumLQR: Pendulum + Controller; Controller.M1/M2 drive Pendulum.M1/M2.
- ``motors`` = PendulumMotors: Pendulum + Controller + two geared DCMotor FMUs; Controller.U1/U2
  -> DCMotor.U, Pendulum.omega_i -> DCMotor.omega, DCMotor.tau -> Pendulum.M_i.

Every run starts from the SSD's parameter values; the experiment's own values are set on top.

Two masters run the same algorithm on the same systems: `NativeClosedLoop` (the default of the
studies) runs the SSP file in-process in the native runner (`rustfmu_runner`, built from
`runner/python` into the venv by tests/setup-env.sh), `ClosedLoop` in the fmpy master below;
the same run gives the same row in both (docs/parameter-studies.md).

The fmpy master is `cosim.master.Loop`, the one fixed-step master of the project's Python side: at
each communication point the connections are evaluated in dependency order (plant outputs ->
controller -> motors -> plant inputs; the Controller's outputs depend directly on its inputs),
then every FMU steps over the same interval. The plant's outputs are states, so there is no
algebraic loop.

The experiment's parameters are set only on the components they name: a perturbed plant is
``pendulum.m1`` etc.; the Controller keeps its nominal plant model and nominal motor model
(it does not know the true plant).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import shutil
import tempfile
import threading
import time
from collections import deque

import numpy as np

from fmpy.fmi1 import FMICallException
from cosim.fmu_log import LogRoute
from cosim.master import Fmu, Loop, System
from cosim.systems import read_ssp, ssp_path

#: The masters a study can run on: the native runner (default) and the fmpy master (the reference).
MASTERS = ("native", "isolated", "isolated-system", "fmpy")

#: The study's names of the systems -> the SSP files fmu-build writes next to the FMUs
#: (`holonomic/systems.toml` describes them: components, parameter values, connections).
SSP_SYSTEMS = {"torque": "PendulumLQR", "motors": "PendulumMotors"}


def study_systems(paths: dict[str, str]) -> dict[str, System]:
    """The study's systems, read from PendulumLQR.ssp and PendulumMotors.ssp next to the
    Pendulum FMU of `paths`; each component's `fmu` is its FMU's model identifier (a key of
    `paths`)."""
    return {name: read_ssp(ssp_path(ssp, paths["Pendulum"])) for name, ssp in SSP_SYSTEMS.items()}


def system_start(system: System) -> dict:
    """The system's start values (the SSD's parameter bindings) as {"component.variable": value}."""
    return {f"{c.name}.{k}": v for c in system.components for k, v in c.start.items()}


STATUS_NAMES = ["OK", "Warning", "Discard", "Error", "Fatal", "Pending"]


@dataclasses.dataclass(frozen=True)
class Criteria:
    """How a run is judged.

    Settled: |alpha1| and |alpha2| stay within `band` rad from some time on to the end of the
    run; the settling time is the first communication point of that final stretch. Stabilized:
    settled at least `hold` s before the end. Fallen: |alpha1| or |alpha2| exceeded `fall` rad
    (the run stops there).
    """

    band: float = 0.01
    hold: float = 0.5
    fall: float = math.pi / 2


class ClosedLoop:
    """A `cosim.master.Loop` of one study system, kept for many runs (fmi2Reset between them),
    with what a study adds: the FMUs' log kept for the error report, an FMU failure returned as a
    row instead of raised, a run stopped when the pendulum falls, and metrics accumulated at each
    communication point instead of recorded arrays."""

    _ids = itertools.count()

    def __init__(self, system: str, description: System, fmus: dict[str, Fmu]):
        self.system = system
        self.id = next(ClosedLoop._ids)
        self.broken = False
        self.log: deque[str] = deque(maxlen=20)
        # One log route for all instances of this loop: keeps the FMUs' messages for error
        # reports, and only this loop's (cosim.fmu_log says why a plain fmpy logger is not enough).
        self._route = LogRoute(self._log_message)
        self.loop = Loop(description, fmus, self._route.callbacks)
        self._state = self.loop.port("pendulum", ("alpha1", "alpha2"))
        # The torque on the plant: the controller's demand, or what the motors deliver.
        motors = [c.name for c in description.components if c.fmu == "DCMotor"]
        if motors:
            self._torque = [self.loop.port(m, ("tau",)) for m in motors]
            self._voltage = self.loop.port("controller", ("U1", "U2"))
        else:
            self._torque = [self.loop.port("controller", ("M1", "M2"))]
            self._voltage = None

    @property
    def runs(self) -> int:
        return self.loop.runs

    def _log_message(self, instance: str, status: int, _category: str, message: str) -> None:
        label = STATUS_NAMES[status] if 0 <= status < len(STATUS_NAMES) else str(status)
        self.log.append(f"[{instance}: {label}] {message}")

    def run(self, start: dict, stop_time: float, step: float, criteria: Criteria = Criteria()) -> dict:
        """One experiment: fmi2Reset (from the second run on), the system's start values and the
        run's own on top (`start` maps "component.variable" to a value,
        e.g. "pendulum.alpha1_0", "pendulum.m1", "controller.mode"), initialization, then
        `stop_time / step` communication steps. Returns the run's metrics; a failure (an FMU
        refusing a value or a step) is returned as status "failed" with the reason, not raised."""
        self.log.clear()
        t0, cpu0 = time.perf_counter(), time.thread_time()
        m = _Metrics(criteria, step, has_voltage=self._voltage is not None)

        def observe(_k, t):
            a1, a2 = self._state.get()
            torque = max(abs(x) for port in self._torque for x in port.get())
            voltage = max(abs(x) for x in self._voltage.get()) if self._voltage is not None else math.nan
            return m.sample(t, a1, a2, torque, voltage)

        try:
            self.loop.run(stop_time, step, start, observe)
        except FMICallException as e:
            # After fmi2Fatal only fmi2FreeInstance is allowed: this loop must not be reused.
            self.broken = self.broken or e.status >= 4
            status = STATUS_NAMES[e.status] if 0 <= e.status < len(STATUS_NAMES) else str(e.status)
            return m.failed(m.t, f"{e}" + self._log_text(), status, e.function, _times(t0, cpu0))
        except Exception as e:  # a bad study specification: recorded like an FMU failure
            return m.failed(m.t, f"{type(e).__name__}: {e}" + self._log_text(), "", "", _times(t0, cpu0))
        return m.result(int(round(stop_time / step)) * step, _times(t0, cpu0))

    def _log_text(self) -> str:
        return (" | FMU log: " + " / ".join(self.log)) if self.log else ""

    def close(self) -> None:
        self.loop.close()
        self._route.close()


class NativeClosedLoop:
    """The runs of `ClosedLoop` on the native runner: `rustfmu_runner.System` on the system's SSP
    file, instantiated once, fmi2Reset between runs, the whole run in Rust with the GIL released.
    It records the plant's angles, the torques and voltages at every communication point and
    stops where the pendulum falls (|alpha| > fall); the metrics are computed from those arrays
    exactly as `_Metrics` computes them one point at a time, so a run gives the row of
    `ClosedLoop`. An FMU failure is returned as a row with the FMI status and function, the
    FMUs' messages in the error text, as there."""

    def __init__(self, system: str, ssp: str, isolate: str | None = None):
        """`isolate`: "component" (each FMU in a child process) or "system" (the whole loop in
        one): an FMU that crashes or hangs fails its run's row, the worker lives on
        (`call_timeout` 60 s per FMU call)."""
        import rustfmu_runner

        self._rf = rustfmu_runner
        self.system = system
        self.id = next(ClosedLoop._ids)
        self.broken = False
        self.runs = 0
        self.sim = rustfmu_runner.System(str(ssp), isolate=isolate, call_timeout=60.0) if isolate else rustfmu_runner.System(str(ssp))
        motors = [name for name, ident in self.sim.components if ident == "DCMotor"]
        if motors:
            self._torque = [f"{m}.tau" for m in motors]
            self._voltage = ["controller.U1", "controller.U2"]
        else:
            self._torque = ["controller.M1", "controller.M2"]
            self._voltage = []
        self._record = ["pendulum.alpha1", "pendulum.alpha2", *self._torque, *self._voltage]

    def run(self, start: dict, stop_time: float, step: float, criteria: Criteria = Criteria()) -> dict:
        """As `ClosedLoop.run`."""
        t0, cpu0 = time.perf_counter(), time.thread_time()
        m = _Metrics(criteria, step, has_voltage=bool(self._voltage))
        self.runs += 1
        stop = {"pendulum.alpha1": criteria.fall, "pendulum.alpha2": criteria.fall}
        try:
            r = self.sim.run(stop_time, step, start=start, record=self._record, stop_when=stop)
        except self._rf.FmuError as e:
            self.broken = self.broken or e.status == "Fatal"
            self._feed(m, e.partial)
            return m.failed(m.t, str(e), e.status or "", e.function or "", _times(t0, cpu0))
        except Exception as e:  # a bad study specification (unknown variable, wrong type)
            return m.failed(m.t, f"{type(e).__name__}: {e}", "", "", _times(t0, cpu0))
        self._feed(m, r)
        return m.result(int(round(stop_time / step)) * step, _times(t0, cpu0))

    def _feed(self, m: "_Metrics", r: dict | None) -> None:
        """`m` as if `_Metrics.sample` had seen every recorded point of `r`."""
        if not r or len(r["time"]) == 0:
            return
        t, a1, a2 = r["time"], r["pendulum.alpha1"], r["pendulum.alpha2"]
        m.t = float(t[-1])
        m.final = (float(a1[-1]), float(a2[-1]))
        m.peak_alpha1 = max(0.0, float(np.abs(a1).max()))
        m.peak_alpha2 = max(0.0, float(np.abs(a2).max()))
        m.peak_torque = max(0.0, float(np.abs(np.stack([r[k] for k in self._torque])).max()))
        if self._voltage:
            m.peak_voltage = max(0.0, float(np.abs(np.stack([r[k] for k in self._voltage])).max()))
        c = m.c
        outside = np.flatnonzero((np.abs(a1) > c.band) | (np.abs(a2) > c.band))
        m.last_outside = float(t[outside[-1]]) if len(outside) else None
        fell = np.flatnonzero((np.abs(a1) > c.fall) | (np.abs(a2) > c.fall))
        m.fell_at = float(t[fell[0]]) if len(fell) else None

    def close(self) -> None:
        self.sim = None


def _times(t0: float, cpu0: float) -> dict:
    """Wall time and this thread's CPU time since t0, cpu0, s."""
    return {"elapsed": time.perf_counter() - t0, "cpu": time.thread_time() - cpu0}


class _Metrics:
    """Running metrics of one run, fed one communication point at a time."""

    def __init__(self, criteria: Criteria, step: float, has_voltage: bool):
        self.c = criteria
        self.step = step
        self.peak_alpha1 = 0.0
        self.peak_alpha2 = 0.0
        self.peak_torque = 0.0
        self.peak_voltage = 0.0 if has_voltage else math.nan
        self.last_outside = None  # time of the last sample outside the band
        self.fell_at = None
        self.t = 0.0
        self.final = (math.nan, math.nan)

    def sample(self, t, a1, a2, torque, voltage) -> bool:
        """Records one communication point; False when the run should stop (fallen)."""
        self.t = t
        self.final = (a1, a2)
        self.peak_alpha1 = max(self.peak_alpha1, abs(a1))
        self.peak_alpha2 = max(self.peak_alpha2, abs(a2))
        self.peak_torque = max(self.peak_torque, torque)
        if not math.isnan(voltage):
            self.peak_voltage = max(self.peak_voltage, voltage)
        if abs(a1) > self.c.band or abs(a2) > self.c.band:
            self.last_outside = t
        if abs(a1) > self.c.fall or abs(a2) > self.c.fall:
            self.fell_at = t
            return False
        return True

    def _common(self, times: dict) -> dict:
        return {
            "t_end": self.t,
            "peak_alpha1": self.peak_alpha1,
            "peak_alpha2": self.peak_alpha2,
            "peak_torque": self.peak_torque,
            "peak_voltage": self.peak_voltage,
            "final_error": math.hypot(*self.final),
            **times,
        }

    def result(self, stop_time: float, times: dict) -> dict:
        if self.fell_at is not None:
            outcome, settling = "fell", math.nan
        else:
            settling = 0.0 if self.last_outside is None else self.last_outside + self.step
            if settling <= stop_time - self.c.hold + 1e-9:
                outcome = "stabilized"
            else:
                outcome, settling = "not_stabilized", math.nan
        return {
            "status": "ok",
            "outcome": outcome,
            "stabilized": outcome == "stabilized",
            "settling_time": settling,
            **self._common(times),
            "fmi_status": "OK",
            "fmi_function": "",
            "error": "",
        }

    def failed(self, t: float, error: str, status: str, function: str, times: dict) -> dict:
        self.t = t
        return {
            "status": "failed",
            "outcome": "failed",
            "stabilized": False,
            "settling_time": math.nan,
            **self._common(times),
            "fmi_status": status,
            "fmi_function": function,
            "error": error,
        }


class FmuSet:
    """The FMU files of a study and a pool of closed loops per system: a loop is taken for a run
    and given back after it, so each thread of a worker instantiates each FMU once and later
    runs reuse it with fmi2Reset. `master`: "native" (`NativeClosedLoop` on the SSP files next
    to the Pendulum FMU, the default), "isolated" (the same, each FMU in a child process),
    "isolated-system" (the whole loop in one child process) or "fmpy" (`ClosedLoop`; each FMU file extracted once into
    `workdir`)."""

    def __init__(self, paths: dict[str, str], workdir: str | None = None, systems: dict[str, System] | None = None, master: str = "native"):
        """`systems`: the study's systems as `study_systems` reads them (default: from the SSP
        files next to `paths["Pendulum"]`); Dask workers get them read by the client."""
        if master not in MASTERS:
            raise ValueError(f"master = {master!r}: one of {MASTERS}")
        self.master = master
        self.paths = dict(paths)
        self.systems = systems if systems is not None else study_systems(paths)
        self._own_workdir = workdir is None
        self.workdir = workdir or tempfile.mkdtemp(prefix="pendulum-study-")
        self.fmus = {ident: Fmu(path, self.workdir) for ident, path in paths.items()} if master == "fmpy" else {}
        self._free: dict[str, list] = {}
        self._lock = threading.Lock()

    def checkout(self, system: str):
        with self._lock:
            free = self._free.setdefault(system, [])
            if free:
                return free.pop()
        if system not in self.systems:
            raise ValueError(f"unknown system '{system}', expected one of {sorted(self.systems)}")
        if self.master in ("native", "isolated", "isolated-system"):
            ssp = str(ssp_path(SSP_SYSTEMS[system], self.paths["Pendulum"]))
            isolate = {"native": None, "isolated": "component", "isolated-system": "system"}[self.master]
            return NativeClosedLoop(system, ssp, isolate=isolate)
        return ClosedLoop(system, self.systems[system], self.fmus)

    def checkin(self, loop) -> None:
        if loop.broken:
            loop.close()
            return
        with self._lock:
            self._free.setdefault(loop.system, []).append(loop)

    def close(self) -> None:
        for loops in self._free.values():
            for loop in loops:
                loop.close()
        self._free.clear()
        if self._own_workdir:
            shutil.rmtree(self.workdir, ignore_errors=True)
