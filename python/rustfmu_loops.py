"""Importer loops for FMI 3.0 FMUs with clocks or structural parameters, on fmpy's classes.

fmpy's `simulate_fmu` (0.3.32) drives neither: in model exchange it never activates an input
clock (the run goes on without a tick, or fails reading a clocked output), in co-simulation it
instantiates without event mode (an FMU with clocks refuses that), and it sets structural
parameters in Instantiated, where FMI 3.0 refuses them (they are set in Configuration Mode), and
sizes arrays by the description's start values. This module is the importer that does both, for
any exporter's FMU (tested on this project's and on the C Reference-FMUs'):

- `simulate_clocked`: model exchange, co-simulation with event mode, or scheduled execution. At
  each tick of an input clock (periodic ones from their interval and shift, triggered ones at the
  times you give, countdown ones when the FMU gives them an interval) the FMU is in Event Mode
  (or `fmi3ActivateModelPartition`): the clock is set active, its clocked inputs set, the output
  clocks asked for, the clocked outputs read while their clock is active, and the discrete states
  updated until the FMU needs no more (eventHandlingNeeded). One row per event, and per output
  point if you ask for them.
- `simulate_configured`: the structural parameters set in Configuration Mode
  (`fmi3EnterConfigurationMode` ... `fmi3ExitConfigurationMode`) before initialization; the arrays'
  start values, inputs and recorded outputs of the sizes those parameters give.

Needs fmpy and numpy only. Copy this file beside your script, or put this folder on `sys.path`.
docs/python.md has the recipe and what each step is for.
"""

from __future__ import annotations

import ctypes
import heapq
import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import fmpy
import numpy as np
from fmpy.fmi3 import (
    FMU3Model,
    FMU3ScheduledExecution,
    FMU3Slave,
    fmi3Boolean,
    fmi3ClockUpdateCallback,
    fmi3InstanceEnvironment,
    fmi3LockPreemptionCallback,
    fmi3LogMessageCallback,
    fmi3UnlockPreemptionCallback,
)

__all__ = ["Result", "simulate_clocked", "simulate_configured"]

INTERFACES = ("ModelExchange", "CoSimulation", "ScheduledExecution")

# fmi3IntervalQualifier
_UNCHANGED, _CHANGED = 1, 2

# FMI 3.0 type -> (numpy dtype, fmpy's get/set suffix): the numbers' dtypes are numpy's of the
# same name (Float64 -> np.float64, UInt8 -> np.uint8, ...).
_NUMBERS = ("Float64", "Float32", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64")
_TYPES = {t: (getattr(np, t.lower()), t) for t in _NUMBERS} | {
    "Enumeration": (np.int64, "Int64"),
    "Boolean": (np.bool_, "Boolean"),
    "String": (object, "String"),
    "Binary": (object, "Binary"),
}


@dataclass
class Result:
    """What a run recorded.

    `rows`: a numpy structured array, field `time` and one field per recorded variable (an array
    variable has the shape its structural parameters gave it). A row per event (after its discrete
    states were updated) and per output point; a clocked variable holds the value read at the
    last tick of one of its clocks. `ticks`: for each clock, the times it ticked (input clocks
    activated, output clocks that said they ticked). `result["y"]` is `result.rows["y"]`."""

    rows: np.ndarray
    ticks: dict[str, list[float]] = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.rows[name]


def simulate_clocked(
    filename: str | Path,
    stop_time: float | None = None,
    *,
    interface: str | None = None,
    start_time: float = 0.0,
    triggers: Mapping[str, Iterable[float]] | None = None,
    inputs: Mapping[str, Any] | None = None,
    start_values: Mapping[str, Any] | None = None,
    structural_parameters: Mapping[str, int] | None = None,
    output: Iterable[str] | None = None,
    output_interval: float | None = None,
    relative_tolerance: float | None = None,
    logger: Callable[[str], None] | None = None,
) -> Result:
    """Run an FMI 3.0 FMU with clocks from `start_time` to `stop_time` (default: the default
    experiment's) and record its outputs at every event.

    `interface`: "ModelExchange", "CoSimulation" (instantiated with eventModeUsed) or
    "ScheduledExecution"; default the first of these the FMU offers. The input clocks tick at
    every time t with start_time <= t <= stop_time their kind gives: a periodic clock
    (intervalVariability constant, fixed or tunable) at shift + k * interval (constant: the
    description's intervalDecimal and shiftDecimal; fixed, tunable: fmi3GetIntervalDecimal and
    fmi3GetShiftDecimal in Initialization Mode); a triggered clock at the times
    `triggers[name]`; a countdown or changing clock at t + h whenever the FMU gives it the
    interval h (fmi3GetIntervalDecimal says fmi3IntervalChanged after an event, or in the
    clockUpdate callback of scheduled execution). Clocks due at the same time tick in the same
    Event Mode (scheduled execution: one activation each, by priority).

    `inputs`: name -> value, or a function of t giving it; a clocked input is set at the ticks of
    its clocks, in Event Mode while the clock is active, any other input at every event and
    output point (a continuous Float input also inside the model-exchange integrator).
    `start_values` are set in Instantiated; `structural_parameters` in Configuration Mode before
    them (as `simulate_configured`). `output`: the names recorded (default: every output but the
    clocks). `output_interval`: also a row every so often (model exchange and co-simulation).
    `relative_tolerance`: model exchange's integrator (default 1e-6; fmpy's CVode); in
    co-simulation it is passed to fmi3EnterInitializationMode (default: none passed, the FMU's
    own integrator keeps its default, which bounds the accuracy between the ticks).
    `logger`: gets each message of the FMU (they are also quoted in the error of a failed call).
    """
    return _Run(
        filename, interface, start_time, stop_time, structural_parameters, start_values,
        inputs, triggers, output, output_interval, relative_tolerance, logger,
    ).run()


def simulate_configured(
    filename: str | Path,
    structural_parameters: Mapping[str, int],
    stop_time: float | None = None,
    *,
    interface: str | None = None,
    start_time: float = 0.0,
    start_values: Mapping[str, Any] | None = None,
    inputs: Mapping[str, Any] | None = None,
    output: Iterable[str] | None = None,
    output_interval: float | None = None,
    triggers: Mapping[str, Iterable[float]] | None = None,
    relative_tolerance: float | None = None,
    logger: Callable[[str], None] | None = None,
) -> Result:
    """Run an FMI 3.0 FMU with its structural parameters (name -> value) set in Configuration Mode.

    (An empty mapping: no Configuration Mode, the description's sizes.) After fmi3InstantiateModelExchange/CoSimulation: fmi3EnterConfigurationMode, the structural
    parameters, fmi3ExitConfigurationMode; then `start_values` (name -> value, an array variable
    as a flat sequence or numpy array of the size the parameters give it: "A" with n = 2 is
    2 x 2, 4 values, whatever the description's start says), initialization, and the run.
    Rows every `output_interval` (default: the default experiment's stepSize, else 1/500 of the
    run) and at events. Model exchange integrates with fmpy's CVode (n states as the parameters
    give); co-simulation steps the FMU. The other arguments are those of `simulate_clocked`
    (an FMU with both clocks and structural parameters works with either function)."""
    run = _Run(
        filename, interface, start_time, stop_time, structural_parameters, start_values,
        inputs, triggers, output, output_interval, relative_tolerance, logger,
    )
    if run.output_interval is None and run.interface != "ScheduledExecution":
        step = run.md.defaultExperiment.stepSize if run.md.defaultExperiment else None
        run.output_interval = float(step) if step else (run.stop - run.start) / 500
    return run.run()


@dataclass
class _Clock:
    vr: int
    name: str
    causality: str
    kind: str  # intervalVariability
    priority: int
    interval: float | None  # description's intervalDecimal
    shift: float  # description's shiftDecimal


class _Inputs:
    """The inputs as fmpy's CVodeSolver wants them (`apply(t)`): the continuous ones."""

    def __init__(self, run: _Run):
        self.run = run

    def apply(self, t, **_):
        self.run._set_inputs(t, continuous_only=True)


class _Run:
    def __init__(self, filename, interface, start, stop, structural, start_values, inputs, triggers, output,
                 output_interval, tolerance, logger):
        self.filename = str(filename)
        self.md = fmpy.read_model_description(self.filename)
        if not self.md.fmiVersion.startswith("3."):
            raise ValueError(f"{self.filename}: FMI {self.md.fmiVersion}; this module runs FMI 3.0 FMUs")
        offered = {
            "ModelExchange": self.md.modelExchange,
            "CoSimulation": self.md.coSimulation,
            "ScheduledExecution": self.md.scheduledExecution,
        }
        if interface is None:
            interface = next((i for i in INTERFACES if offered[i] is not None), None)
        if interface not in INTERFACES:
            raise ValueError(f"interface {interface!r}: one of {', '.join(INTERFACES)}")
        if offered[interface] is None:
            have = ", ".join(i for i in INTERFACES if offered[i] is not None)
            raise ValueError(f"{self.filename} does not offer {interface} (it offers {have})")
        self.interface = interface
        self.identifier = offered[interface].modelIdentifier
        self.unzipdir = fmpy.extract(self.filename)
        self.var = {v.name: v for v in self.md.modelVariables}
        self.by_vr = {v.valueReference: v for v in self.md.modelVariables}
        self.clocks = self._read_clocks()
        self.start = float(start)
        experiment = self.md.defaultExperiment
        if stop is None:
            stop = experiment.stopTime if experiment and experiment.stopTime is not None else 1.0
        self.stop = float(stop)
        if not self.stop >= self.start:
            raise ValueError(f"stop_time {self.stop} is before start_time {self.start}")
        self.structural = dict(structural or {})
        self.start_values = dict(start_values or {})
        self.inputs = dict(inputs or {})
        self.output_interval = output_interval
        self.tolerance = tolerance
        self.logger = logger
        self.messages: list[str] = []
        for name in [*self.structural, *self.start_values, *self.inputs]:
            self._variable(name)
        for name, value in self.structural.items():
            if self.var[name].causality != "structuralParameter":
                raise ValueError(f"'{name}' is a {self.var[name].causality}, not a structural parameter")
        for name in self.inputs:
            if self.var[name].causality != "input":
                raise ValueError(f"inputs: '{name}' is a {self.var[name].causality}, not an input")
        self.triggered = {}
        for name, times in (triggers or {}).items():
            c = self.clocks.get(name)
            if c is None or c.causality != "input" or c.kind != "triggered":
                raise ValueError(f"triggers: '{name}' is no triggered input clock of {self.filename} "
                                 f"(those are: {', '.join(self._clock_names('triggered')) or 'none'})")
            self.triggered[c.vr] = sorted(float(t) for t in times)
        if output is None:
            output = [v.name for v in self.md.modelVariables if v.causality == "output" and v.type != "Clock"]
        self.output = list(output)
        for name in self.output:
            if self._variable(name).type == "Clock":
                raise ValueError(f"output: '{name}' is a Clock; its ticks are in Result.ticks")
        self.shapes = {name: self._shape(self.var[name]) for name in self.output}
        self.held = {name: self._initial(self.var[name]) for name in self.output}
        self.ticks: dict[str, list[float]] = {c.name: [] for c in self.clocks.values()}
        self.rows: list[tuple] = []

    # -- the description -------------------------------------------------------------------

    def _variable(self, name):
        v = self.var.get(name)
        if v is None:
            raise ValueError(f"{self.filename} has no variable '{name}'")
        return v

    def _clock_names(self, kind):
        return [c.name for c in self.clocks.values() if c.causality == "input" and c.kind == kind]

    def _read_clocks(self):
        # From the file itself: fmpy 0.3.32 leaves `priority` unread.
        root = ET.parse(Path(self.unzipdir) / "modelDescription.xml").getroot()
        clocks = {}
        for c in root.iter("Clock"):
            name = c.get("name")
            clocks[name] = _Clock(
                vr=int(c.get("valueReference")),
                name=name,
                causality=c.get("causality", "local"),
                kind=c.get("intervalVariability"),
                priority=int(c.get("priority", "0")),
                interval=float(c.get("intervalDecimal")) if c.get("intervalDecimal") is not None else None,
                shift=float(c.get("shiftDecimal", "0")),
            )
        return clocks

    def _size_of(self, vr):
        """The value of the structural parameter `vr`: as set, else its start."""
        v = self.by_vr[vr]
        return int(self.structural.get(v.name, v.start))

    def _shape(self, v):
        return tuple(int(d.start) if d.start is not None else self._size_of(d.valueReference) for d in v.dimensions)

    def _initial(self, v):
        """A clocked variable's value before its first tick: its start, else zero."""
        dtype = _TYPES[v.type][0]
        shape = self._shape(v)
        if v.start is None:
            return np.zeros(shape, dtype=dtype) if shape else (None if dtype is object else dtype(0))
        parts = v.start.split() if v.type not in ("String", "Binary") else [v.start]
        if v.type == "Boolean":
            parts = [p in ("true", "1") for p in parts]
        value = np.asarray(parts).astype(dtype) if dtype is not object else np.asarray(parts, dtype=object)
        n = int(np.prod(shape)) if shape else 1
        if value.size != n:
            # The start list is for the description's sizes, not for the configured ones.
            return np.zeros(shape, dtype=dtype)
        return value.reshape(shape) if shape else value[0]

    def _clocked_by(self, v):
        return [c.valueReference for c in (v.clocks or [])]

    # -- getting and setting -----------------------------------------------------------------

    def _get(self, name):
        v = self.var[name]
        shape = self.shapes.get(name) or self._shape(v)
        n = int(np.prod(shape)) if shape else 1
        values = getattr(self.fmu, "get" + _TYPES[v.type][1])([v.valueReference], nValues=n)
        if not shape:
            return values[0]
        return np.asarray(values, dtype=_TYPES[v.type][0]).reshape(shape)

    def _set(self, name, value, where):
        v = self.var[name]
        shape = self._shape(v)
        dtype, kind = _TYPES[v.type]
        flat = np.ravel(np.asarray(value, dtype=dtype if dtype is not object else object))
        n = int(np.prod(shape)) if shape else 1
        if flat.size != n:
            sizes = " x ".join(str(s) for s in shape) or "1"
            given = ", ".join(dict.fromkeys(f"{self.by_vr[d.valueReference].name} = {self._size_of(d.valueReference)}"
                                            for d in v.dimensions if d.start is None))
            raise ValueError(f"{where}: '{name}' has {sizes} = {n} element(s)"
                             f"{' (' + given + ')' if given else ''}; {flat.size} value(s) were given")
        getattr(self.fmu, "set" + kind)([v.valueReference], flat.tolist())

    def _value_at(self, source, t):
        return source(t) if callable(source) else source

    def _set_inputs(self, t, continuous_only=False, clocks=None):
        """The inputs at t: unclocked ones (continuous Float ones only, if `continuous_only`), or
        those clocked by one of `clocks`."""
        for name, source in self.inputs.items():
            v = self.var[name]
            by = self._clocked_by(v)
            if clocks is not None:
                if by and set(by) & clocks:
                    self._set(name, self._value_at(source, t), f"input at t = {t}")
                continue
            if by or (continuous_only and (v.variability != "continuous" or not v.type.startswith("Float"))):
                continue
            self._set(name, self._value_at(source, t), f"input at t = {t}")

    def _record(self, t, active=frozenset()):
        """Read what can be read now (unclocked outputs; clocked ones whose clock is active) and
        add a row."""
        for name in self.output:
            by = self._clocked_by(self.var[name])
            if not by or set(by) & active:
                self.held[name] = self._get(name)
        self.rows.append((t, *[self.held[name] for name in self.output]))

    def _result(self):
        dtype = [("time", np.float64)]
        for name in self.output:
            base = _TYPES[self.var[name].type][0]
            dtype.append((name, base, self.shapes[name]) if self.shapes[name] else (name, base))
        return Result(rows=np.array(self.rows, dtype=dtype), ticks=self.ticks)

    # -- instantiation, configuration, initialization ----------------------------------------

    def _log(self, env, status, category, message):
        text = message.decode(errors="replace") if isinstance(message, bytes) else str(message)
        self.messages.append(text)
        if self.logger:
            self.logger(text)

    def _instantiate(self):
        kwargs = dict(guid=self.md.guid, unzipDirectory=self.unzipdir, modelIdentifier=self.identifier,
                      instanceName=Path(self.filename).stem)
        if self.interface == "ModelExchange":
            self.fmu = FMU3Model(**kwargs)
            self.fmu.instantiate(logMessage=self._log)
        elif self.interface == "CoSimulation":
            self.fmu = FMU3Slave(**kwargs)
            # An FMU with clocks runs with event mode: the ticks are Event Mode's (FMI 3.0, 4.2.1).
            self.event_mode = any(c.causality == "input" for c in self.clocks.values())
            self.fmu.instantiate(eventModeUsed=self.event_mode, logMessage=self._log)
        else:
            self.fmu = FMU3ScheduledExecution(**kwargs)
            # fmpy's own instantiate gives the FMU a clockUpdate callback that does nothing: ours
            # hears the output clocks and the countdown intervals.
            self._callbacks = (
                fmi3LogMessageCallback(self._log),
                fmi3ClockUpdateCallback(self._clock_update),
                fmi3LockPreemptionCallback(lambda: None),
                fmi3UnlockPreemptionCallback(lambda: None),
            )
            self.fmu.component = self.fmu.fmi3InstantiateScheduledExecution(
                self.fmu.instanceName.encode(), self.md.guid.encode(),
                (str(Path(self.unzipdir) / "resources") + "/").encode(),
                fmi3Boolean(False), fmi3Boolean(False), fmi3InstanceEnvironment(), *self._callbacks,
            )
            if not self.fmu.component:
                raise RuntimeError("fmi3InstantiateScheduledExecution returned NULL")

    def _configure(self):
        if not self.structural:
            return
        self.fmu.enterConfigurationMode()
        for name, value in self.structural.items():
            try:
                self._set(name, value, "Configuration Mode")
            except Exception as e:
                raise RuntimeError(f"setting structural parameter '{name}' = {value} in Configuration Mode: {e}") from e
        self.fmu.exitConfigurationMode()

    def _interval(self, vr):
        h, q = (ctypes.c_double * 1)(), (ctypes.c_int * 1)()
        self.fmu.getIntervalDecimal((ctypes.c_uint * 1)(vr), h, q)
        return h[0], q[0]

    def _shift(self, vr):
        s = (ctypes.c_double * 1)()
        self.fmu.getShiftDecimal((ctypes.c_uint * 1)(vr), s)
        return s[0]

    def _initialize(self):
        for name, value in self.start_values.items():
            self._set(name, value, "start values")
        self.fmu.enterInitializationMode(
            tolerance=self.tolerance if self.interface == "CoSimulation" else None,
            startTime=self.start, stopTime=self.stop)
        self._set_inputs(self.start)
        # The periodic input clocks: interval and shift as the standard says where to find them.
        self.periodic = {}
        for c in self.clocks.values():
            if c.causality != "input" or c.kind not in ("constant", "fixed", "tunable"):
                continue
            if c.kind == "constant":
                if c.interval is None:
                    raise ValueError(f"constant clock '{c.name}' without intervalDecimal (fractions are not read here)")
                h, shift = c.interval, c.shift
            else:
                h, q = self._interval(c.vr)
                if q not in (_UNCHANGED, _CHANGED) or not h > 0:
                    raise RuntimeError(f"clock '{c.name}': fmi3GetIntervalDecimal gave {h} (qualifier {q}) "
                                       "in Initialization Mode")
                shift = self._shift(c.vr)
            self.periodic[c.vr] = (shift, h)
        self.fmu.exitInitializationMode()

    # -- the schedule ------------------------------------------------------------------------

    def _eps(self, t):
        return 1e-9 * max(1.0, abs(t))

    def _due_periodic(self, vr, t):
        shift, h = self.periodic[vr]
        k = round((t - self.start - shift) / h)
        return k >= 0 and abs(self.start + shift + k * h - t) <= self._eps(t)

    def _next_periodic(self, vr, t):
        """The first tick after t."""
        shift, h = self.periodic[vr]
        k = max(0, math.floor((t - self.start - shift) / h + 1e-9) + 1)
        tk = self.start + shift + k * h
        return tk if tk > t + self._eps(t) else self.start + shift + (k + 1) * h

    def _due(self, t):
        """The input clocks that tick at t and have not yet (a countdown clock given the interval
        0 ticks again)."""
        fresh = {vr for vr in self.periodic if self._due_periodic(vr, t)}
        fresh |= {vr for vr, times in self.triggered.items() if any(abs(x - t) <= self._eps(t) for x in times)}
        fresh = {vr for vr in fresh if self.last_tick.get(vr) != t}
        return fresh | {vr for vr, at in self.countdown.items() if at is not None and at <= t + self._eps(t)}

    def _next_time(self, t):
        candidates = [self._next_periodic(vr, t) for vr in self.periodic]
        candidates += [x for times in self.triggered.values() for x in times if x > t + self._eps(t)]
        candidates += [at for at in self.countdown.values() if at is not None and at > t + self._eps(t)]
        if self.time_event is not None and self.time_event > t + self._eps(t):
            candidates.append(self.time_event)
        return min(candidates, default=math.inf)

    def _aperiodic_intervals(self, t):
        """A countdown or changing clock given a new interval h ticks at t + h."""
        for c in self.clocks.values():
            if c.causality == "input" and c.kind in ("countdown", "changing"):
                h, q = self._interval(c.vr)
                if q == _CHANGED:
                    self.countdown[c.vr] = t + h

    # -- model exchange and co-simulation ------------------------------------------------------

    def _event(self, t):
        """The FMU is in Event Mode at t: the clocks due tick (several rounds if a countdown
        clock is due again at once), the discrete states are updated until the FMU needs no
        more, a row is recorded."""
        outputs = [c for c in self.clocks.values() if c.causality == "output"]
        for _ in range(1000):
            due = self._due(t)
            self._set_inputs(t)
            if due:
                self.fmu.setClock(sorted(due), [True] * len(due))
                self._set_inputs(t, clocks=due)
                for vr in due:
                    self.ticks[self.by_vr[vr].name].append(t)
                    self.countdown.pop(vr, None)
            active = set(due)
            if outputs:
                for c, on in zip(outputs, self.fmu.getClock([c.vr for c in outputs])):
                    if on:
                        active.add(c.vr)
                        self.ticks[c.name].append(t)
            self._record(t, active)
            while True:
                again, terminate, _, _, defined, next_time = self.fmu.updateDiscreteStates()
                if terminate:
                    self.terminated = True
                    return
                if not again:
                    break
            self.time_event = next_time if defined else None
            for vr in due:
                self.last_tick[vr] = t
            self._aperiodic_intervals(t)
            if not self._due(t):
                return
        raise RuntimeError(f"t = {t}: clocks still due after 1000 rounds of Event Mode")

    def _me(self):
        fmu = self.fmu
        nx, nz = fmu.getNumberOfContinuousStates(), fmu.getNumberOfEventIndicators()
        self._event(self.start)
        if self.terminated:
            return
        fmu.enterContinuousTimeMode()
        solver = None
        if nx or nz:
            from fmpy.sundials import CVodeSolver

            def set_time(t):
                fmu.setTime(t)
                self._set_inputs(t, continuous_only=True)

            solver = CVodeSolver(
                nx=nx, nz=nz, get_x=fmu.getContinuousStates, set_x=fmu.setContinuousStates,
                get_dx=fmu.getContinuousStateDerivatives, get_z=fmu.getEventIndicators,
                get_nominals=fmu.getNominalsOfContinuousStates, set_time=set_time, input=_Inputs(self),
                startTime=self.start, maxStep=(self.stop - self.start) / 50 or math.inf,
                relativeTolerance=self.tolerance or 1e-6)
        t = self.start
        while t < self.stop - self._eps(self.stop):
            target = min(self._next_time(t), self._next_output(t), self.stop)
            if solver:
                state_event, _, t = solver.step(t, target)
            else:
                state_event, t = False, target
            fmu.setTime(t)
            self._set_inputs(t, continuous_only=True)
            step_event, terminate = fmu.completedIntegratorStep()
            if terminate:
                break
            if state_event or step_event or self._due(t) or self._time_event_at(t):
                fmu.enterEventMode()
                self._event(t)
                if self.terminated:
                    break
                fmu.enterContinuousTimeMode()
                if solver:
                    solver.reset(t)
            elif self._on_output_grid(t) or t >= self.stop - self._eps(self.stop):
                self._record(t)

    def _cs(self):
        fmu = self.fmu
        if self.event_mode:
            self._event(self.start)
            if self.terminated:
                return
            fmu.enterStepMode()
        else:
            self._record(self.start)
        t = self.start
        while t < self.stop - self._eps(self.stop):
            target = min(self._next_time(t), self._next_output(t), self.stop)
            self._set_inputs(t)
            event, terminate, early, last = fmu.doStep(currentCommunicationPoint=t, communicationStepSize=target - t)
            if terminate:
                break
            t = last if early else target
            if self.event_mode and (event or self._due(t) or self._time_event_at(t)):
                fmu.enterEventMode()
                self._event(t)
                if self.terminated:
                    break
                fmu.enterStepMode()
            elif self._on_output_grid(t) or t >= self.stop - self._eps(self.stop):
                self._record(t)

    def _time_event_at(self, t):
        return self.time_event is not None and self.time_event <= t + self._eps(t)

    def _next_output(self, t):
        if not self.output_interval:
            return math.inf
        k = math.floor((t - self.start) / self.output_interval + 1e-9) + 1
        return self.start + k * self.output_interval

    def _on_output_grid(self, t):
        if not self.output_interval:
            return False
        k = round((t - self.start) / self.output_interval)
        return abs(self.start + k * self.output_interval - t) <= self._eps(t)

    # -- scheduled execution -------------------------------------------------------------------

    def _clock_update(self, env):
        # Called by the FMU from inside fmi3ActivateModelPartition (Clock Update Mode): the
        # output clocks and the countdown intervals, read now. An exception cannot cross the C
        # callback: it is kept and raised when the activation returns.
        try:
            t = self.now
            outputs = [c for c in self.clocks.values() if c.causality == "output"]
            ticking = set()
            if outputs:
                for c, on in zip(outputs, self.fmu.getClock([c.vr for c in outputs])):
                    if on:
                        ticking.add(c.vr)
                        self.ticks[c.name].append(t)
            for name in self.output:
                if set(self._clocked_by(self.var[name])) & ticking:
                    self.held[name] = self._get(name)
            for c in self.clocks.values():
                if c.causality == "input" and c.kind in ("countdown", "changing"):
                    h, q = self._interval(c.vr)
                    if q == _CHANGED:
                        self._schedule(t + h, c.vr)
        except BaseException as e:  # noqa: BLE001 (raised again after the activation)
            self.callback_error = e

    def _schedule(self, t, vr):
        """Scheduled execution: an activation of `vr` at t, in time and then priority order."""
        if t <= self.stop + self._eps(self.stop):
            self.seq += 1
            heapq.heappush(self.queue, (t, self.clocks[self.by_vr[vr].name].priority, self.seq, vr))

    def _se(self):
        self.queue, self.seq = [], 0
        for vr, (shift, h) in self.periodic.items():
            k = 0
            while self.start + shift + k * h <= self.stop + self._eps(self.stop):
                self._schedule(self.start + shift + k * h, vr)
                k += 1
        for vr, times in self.triggered.items():
            for t in times:
                if t >= self.start - self._eps(self.start):
                    self._schedule(t, vr)
        while self.queue:
            t, _, _, vr = heapq.heappop(self.queue)
            self.now = t
            self._set_inputs(t)
            self._set_inputs(t, clocks={vr})
            self.callback_error = None
            self.fmu.activateModelPartition(vr, t)
            if self.callback_error is not None:
                raise self.callback_error
            self.ticks[self.by_vr[vr].name].append(t)
            self._record(t, {vr})

    # -- the run ----------------------------------------------------------------------------

    def run(self) -> Result:
        self.fmu = None
        self.event_mode = self.interface == "ModelExchange"
        self.time_event = None
        self.countdown: dict[int, float | None] = {}
        self.last_tick: dict[int, float] = {}
        self.terminated = False
        try:
            self._instantiate()
            self._configure()
            self._initialize()
            if self.interface == "ModelExchange":
                self._me()
            elif self.interface == "CoSimulation":
                self._cs()
            else:
                self._se()
            self.fmu.terminate()
        except Exception as e:
            said = "; ".join(self.messages[-3:])
            raise RuntimeError(f"{self.filename} ({self.interface}): {e}" + (f"; the FMU said: {said}" if said else "")) from e
        finally:
            if self.fmu is not None and self.fmu.component:
                self.fmu.freeInstance()
                self.fmu.component = None
        return self._result()
