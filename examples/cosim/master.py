"""A fixed-step co-simulation master for FMI 2.0 and FMI 3.0 co-simulation FMUs, on fmpy's
FMU2Slave and FMU3Slave.

A communication point is evaluated in dependency order (Gauss-Seidel along the connections):
the components are sorted so that every component whose outputs depend directly on a connected
input (ModelStructure `dependencies`; the Controller's M, U on the measured state) comes after
the components feeding it; each component's inputs are set from the freshly read outputs of the
components before it, then its outputs are read; inputs from components later in the order
(which, by the sort, do not feed through) are set last. For the paper's loops that is plant
outputs -> controller -> motors -> plant inputs; then every FMU steps over the same interval. A
cycle of direct feedthrough (an algebraic loop) is refused. `order="jacobi"` keeps the old
scheme (read every output, then set every input), which makes every feedthrough a one-step delay.
In initialization mode the connections are propagated once per component.

`Loop` is the one master loop of the project's Python side: `simulate` runs it once on fresh
instances; the parameter study (`examples/pendulum_study/closed_loop.py`) keeps loops alive and
runs many experiments on each (fmi2Reset between them).

Clocks (FMI 3.0): a component with periodic input clocks (the SampledController's `sample`)
runs with eventModeUsed; the master reads each clock's interval and shift in Initialization Mode
and requires its ticks to fall on communication points. At a communication point where a clock
ticks, the instance is in Event Mode: fmi3SetClock, then the connections (its clocked inputs are
set, its clocked outputs read), then fmi3UpdateDiscreteStates and fmi3EnterStepMode before it
steps. Between the ticks its clocked inputs are not set and its clocked outputs hold the values
read at the last tick (they cannot be read there).

The FMI version is each FMU's own (its modelDescription's fmiVersion): a 2.0 FMU runs on
FMU2Slave (fmi2SetupExperiment, then fmi2EnterInitializationMode; Real, Integer, Enumeration
through fmi2SetInteger), a 3.0 FMU on FMU3Slave (fmi3EnterInitializationMode with the same start
and stop time and no tolerance, as the 2.0 loop gives none; Float64, Int32, Enumeration through
fmi3SetInt64). The algorithm is the same call for call, so a loop of the 3.0 FMUs gives the
numbers of the loop of their 2.0 twins (docs/fmi3.md), and one loop may mix the versions.
"""

from __future__ import annotations

import ctypes
import dataclasses
import shutil
import tempfile

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

#: The FMI types of a Real (FMI 2.0) and a Float64 (FMI 3.0) variable: what a connection carries.
FLOAT = ("Real", "Float64")


@dataclasses.dataclass(frozen=True)
class Component:
    """One FMU instance: its name in the system, the .fmu file, and start values to set."""

    name: str
    fmu: str
    start: dict = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class Connection:
    """Output `source_var` of component `source` drives input `target_var` of `target`."""

    source: str
    source_var: str
    target: str
    target_var: str


@dataclasses.dataclass(frozen=True)
class System:
    name: str
    components: tuple[Component, ...]
    connections: tuple[Connection, ...]


class Fmu:
    """One FMU file extracted once (into `workdir`, default a new temporary directory), with its
    variables by name. Several instances, in one loop or in several, may share it."""

    def __init__(self, path: str, workdir: str | None = None):
        self.path = path
        self.md = read_model_description(path)
        if self.md.coSimulation is None:
            raise ValueError(f"{path}: the FMU has no co-simulation interface")
        if self.md.fmiVersion not in ("2.0",) and not self.md.fmiVersion.startswith("3."):
            raise ValueError(f"{path}: FMI {self.md.fmiVersion}: the master runs FMI 2.0 and 3.0 FMUs")
        self.fmi3 = self.md.fmiVersion.startswith("3.")
        # FMI 3.0 clocks: the input clocks the master activates, the clocked variables.
        self.clocks = [v for v in self.md.modelVariables if v.type == "Clock"]
        for c in self.clocks:
            if c.causality != "input" or c.intervalVariability not in ("constant", "fixed", "tunable"):
                raise ValueError(f"{path}: clock '{c.name}' ({c.causality}, {c.intervalVariability}): the master activates periodic input clocks only")
        self.clocked = {v.valueReference for v in self.md.modelVariables if getattr(v, "clocks", None)}
        self.dir = extract(path, unzipdir=tempfile.mkdtemp(prefix=self.md.coSimulation.modelIdentifier + "-", dir=workdir))
        self.vars = {v.name: v for v in self.md.modelVariables}

    def var(self, name: str):
        try:
            return self.vars[name]
        except KeyError:
            raise KeyError(f"{self.md.modelName} has no variable '{name}'") from None

    def close(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)


class RealPort:
    """A fixed list of Real (FMI 2.0) or Float64 (FMI 3.0) value references of one instance, read
    or written through ctypes arrays built once. fmpy's getReal builds both arrays on every call:
    10 us per call against 4 us here (measured, 4 values), and a run makes about ten such calls
    per communication point."""

    def __init__(self, slave: FMU2Slave | FMU3Slave, vrs: list[int], clocked=frozenset(), ticking=None):
        self.slave = slave
        self.fmi3 = isinstance(slave, FMU3Slave)
        self.n = len(vrs)
        self.vr = (ctypes.c_uint * self.n)(*vrs)
        self.buf = (ctypes.c_double * self.n)()
        # Clocked variables (FMI 3.0) are read and set while their instance ticks (`ticking()`)
        # only; between the ticks a read gives the values of the last tick, a set sets the others.
        self.clocked = [vr in clocked for vr in vrs]
        self.ticking = ticking if any(self.clocked) else None
        self.held = (ctypes.c_double * self.n)()
        self.free = [vr for vr, c in zip(vrs, self.clocked) if not c]

    def get(self):
        if self.ticking is not None and not self.ticking():
            if self.free:
                values = iter(self.slave.getFloat64(self.free))
                for i, c in enumerate(self.clocked):
                    if not c:
                        self.held[i] = next(values)
            return self.held
        if self.fmi3:
            self.slave.fmi3GetFloat64(self.slave.component, self.vr, self.n, self.buf, self.n)
        else:
            self.slave.fmi2GetReal(self.slave.component, self.vr, self.n, self.buf)
        if self.ticking is not None:
            ctypes.memmove(self.held, self.buf, ctypes.sizeof(self.buf))
        return self.buf

    def set(self, values) -> None:
        if self.ticking is not None and not self.ticking():
            free = [(vr, x) for vr, c, x in zip(self.vr, self.clocked, values) if not c]
            if free:
                self.slave.setFloat64([vr for vr, _ in free], [x for _, x in free])
            return
        for i, x in enumerate(values):
            self.buf[i] = x
        if self.fmi3:
            self.slave.fmi3SetFloat64(self.slave.component, self.vr, self.n, self.buf, self.n)
        else:
            self.slave.fmi2SetReal(self.slave.component, self.vr, self.n, self.buf)


class Loop:
    """The FMU instances of `system`, instantiated once; `run` is one experiment on them, and
    every run after the first starts with fmi2Reset, so one loop can run many experiments.

    `fmus` maps each component's `fmu` to an extracted `Fmu` (shared, e.g. by a pool of loops);
    None extracts the system's FMU files here, removed again by `close`. `callbacks`: where the
    instances log: a `cosim.fmu_log.LogRoute` (FMI 2.0 and 3.0 instances), or fmpy
    fmi2CallbackFunctions (FMI 2.0 instances only); None: fmpy's defaults (print)."""

    ORDERS = ("gauss-seidel", "jacobi")

    def __init__(self, system: System, fmus: dict[str, Fmu] | None = None, callbacks=None, order: str = "gauss-seidel"):
        if order not in self.ORDERS:
            raise ValueError(f"order = {order!r}: one of {self.ORDERS}")
        self.system = system
        self.order = order
        self.runs = 0
        self._own = {}
        if fmus is None:
            for c in system.components:
                if c.fmu not in self._own:
                    self._own[c.fmu] = Fmu(c.fmu)
            fmus = self._own
        self.fmus = {c.name: fmus[c.fmu] for c in system.components}
        self.start = {f"{c.name}.{k}": v for c in system.components for k, v in c.start.items()}
        self.slaves: dict[str, FMU2Slave | FMU3Slave] = {}
        # Clocked instances: their clocks' (value reference, shift, interval), and whether each
        # is in Event Mode (ticking: at a tick; or right after initialization).
        self._ticks: dict[str, list[tuple[int, float, float]]] = {}
        self._ticking: dict[str, bool] = {}
        self._in_event_mode: dict[str, bool] = {}
        self._held: dict[tuple[str, int], float] = {}
        try:
            for name, fmu in self.fmus.items():
                cls = FMU3Slave if fmu.fmi3 else FMU2Slave
                slave = cls(
                    guid=fmu.md.guid,
                    unzipDirectory=fmu.dir,
                    modelIdentifier=fmu.md.coSimulation.modelIdentifier,
                    instanceName=name,
                )
                if fmu.fmi3:
                    # With clocks, eventModeUsed is required (FMI 3.0, 4.2.1).
                    slave.instantiate(loggingOn=False, logMessage=_fmi3_logger(callbacks, name),
                                      eventModeUsed=bool(fmu.clocks))
                else:
                    slave.instantiate(callbacks=getattr(callbacks, "callbacks", callbacks), loggingOn=False)
                self.slaves[name] = slave
            self._build_ports()
        except BaseException:
            self.close()
            raise

    def var(self, component: str, name: str):
        if component not in self.fmus:
            raise KeyError(f"'{component}.{name}': system {self.system.name} has no component '{component}' (has {sorted(self.fmus)})")
        return self.fmus[component].var(name)

    def fmi_version(self, component: str) -> str:
        """The FMI version of `component`'s FMU ("2.0", "3.0")."""
        return self.fmus[component].md.fmiVersion

    def port(self, component: str, names) -> RealPort:
        """A RealPort on Real (Float64) variables `names` of `component`."""
        return RealPort(self.slaves[component], [self.var(component, v).valueReference for v in names],
                        self.fmus[component].clocked, lambda: self._ticking.get(component, False))

    def feeds_through(self, component: str, inputs) -> bool:
        """Whether an output of `component` depends directly on one of `inputs` (its
        ModelStructure; an output without a `dependencies` attribute depends on every input)."""
        inputs = set(inputs)
        for unknown in self.fmus[component].md.outputs:
            if unknown.dependencies is None or inputs & {d.name for d in unknown.dependencies}:
                return True
        return False

    def evaluation_order(self) -> list[str]:
        """The components, each after those whose outputs it feeds through (a topological sort
        of the direct-feedthrough graph, stable in the system's order); ValueError on a cycle."""
        names = [c.name for c in self.system.components]
        feeds: dict[str, set[str]] = {n: set() for n in names}  # target -> sources it must follow
        by_pair: dict[tuple[str, str], list[str]] = {}
        for k in self.system.connections:
            by_pair.setdefault((k.target, k.source), []).append(k.target_var)
        for (target, source), inputs in by_pair.items():
            if self.feeds_through(target, inputs):
                feeds[target].add(source)
        order: list[str] = []
        while len(order) < len(names):
            ready = [n for n in names if n not in order and feeds[n] <= set(order)]
            if not ready:
                left = sorted(n for n in names if n not in order)
                raise ValueError(f"{self.system.name}: algebraic loop (direct feedthrough in a cycle) among {left}")
            order.append(ready[0])
        return order

    def _build_ports(self) -> None:
        """Groups the connections so that each communication point reads each source once and
        writes each (target, source) pair once. Every connection of these systems carries a Real
        (FMI 2.0) or Float64 (FMI 3.0)."""
        sources: dict[str, list[str]] = {}
        pairs: dict[tuple[str, str], list[tuple[str, str]]] = {}
        for k in self.system.connections:
            for c, v in ((k.source, k.source_var), (k.target, k.target_var)):
                if self.var(c, v).type not in FLOAT:
                    raise TypeError(f"{self.system.name}: connection {k.source}.{k.source_var} -> {k.target}.{k.target_var}: {c}.{v} is not Real (Float64)")
            if k.source_var not in sources.setdefault(k.source, []):
                sources[k.source].append(k.source_var)
            pairs.setdefault((k.target, k.source), []).append((k.target_var, k.source_var))
        self._reads = {c: self.port(c, vs) for c, vs in sources.items()}
        index = {(c, v): i for c, vs in sources.items() for i, v in enumerate(vs)}
        writes = {pair: (self.port(pair[0], [i for i, _ in conns]), pair[1], [index[(pair[1], o)] for _, o in conns]) for pair, conns in pairs.items()}
        self._all_writes = list(writes.values())
        # Gauss-Seidel: before reading component c, set its inputs from the components read
        # before it; after all reads, the inputs from components later in the order.
        self._order = self.evaluation_order()
        position = {c: i for i, c in enumerate(self._order)}
        self._steps = [(c, [w for (t, src), w in writes.items() if t == c and position[src] < position[c]]) for c in self._order]
        self._late = [w for (t, src), w in writes.items() if position[src] >= position[t]]

    def propagate(self) -> None:
        """Sets every connected input from its output: in dependency order (Gauss-Seidel), or
        with `order="jacobi"` every output read first."""
        values: dict[str, list[float]] = {}
        if self.order == "jacobi":
            values = {c: list(port.get()) for c, port in self._reads.items()}
            writes = self._all_writes
        else:
            for c, before in self._steps:
                for port, src, idx in before:
                    v = values[src]
                    port.set([v[i] for i in idx])
                if c in self._reads:
                    values[c] = list(self._reads[c].get())
            writes = self._late
        for port, src, idx in writes:
            v = values[src]
            port.set([v[i] for i in idx])

    def set(self, qualified: str, value) -> None:
        """Sets "component.variable" to `value`, converted to the variable's type."""
        component, _, name = qualified.partition(".")
        v = self.var(component, name)
        slave = self.slaves[component]
        fmi3 = self.fmus[component].fmi3
        if v.type == "Real":
            slave.setReal([v.valueReference], [float(value)])
        elif v.type == "Float64":
            slave.setFloat64([v.valueReference], [float(value)])
        elif v.type == "Integer":
            slave.setInteger([v.valueReference], [int(value)])
        elif v.type == "Int32":
            slave.setInt32([v.valueReference], [int(value)])
        elif v.type == "Enumeration":
            # An item's value, or its name ("LQR").
            if isinstance(value, str):
                items = {item.name: int(item.value) for item in v.declaredType.items}
                if value not in items:
                    raise ValueError(f"{qualified}: '{value}' is no item of {v.declaredType.name} ({', '.join(items)})")
                value = items[value]
            # FMI 2.0: fmi2SetInteger; FMI 3.0: fmi3SetInt64.
            (slave.setInt64 if fmi3 else slave.setInteger)([v.valueReference], [int(value)])
        elif v.type == "Boolean":
            slave.setBoolean([v.valueReference], [bool(value)])
        else:
            raise TypeError(f"{qualified}: unsupported type {v.type}")

    def get(self, component: str, name: str):
        v = self.var(component, name)
        slave = self.slaves[component]
        if v.valueReference in self.fmus[component].clocked:
            # A clocked variable: read at a tick, held between them.
            key = (component, v.valueReference)
            if self._ticking.get(component, False) or key not in self._held:
                self._held[key] = slave.getFloat64([v.valueReference])[0] if v.type == "Float64" else self._plain_get(component, v)
            return self._held[key]
        return self._plain_get(component, v)

    def _plain_get(self, component: str, v):
        slave = self.slaves[component]
        name = v.name
        if v.type == "Real":
            return slave.getReal([v.valueReference])[0]
        if v.type == "Float64":
            return slave.getFloat64([v.valueReference])[0]
        if v.type == "Integer":
            return slave.getInteger([v.valueReference])[0]
        if v.type == "Int32":
            return slave.getInt32([v.valueReference])[0]
        if v.type == "Enumeration":
            return (slave.getInt64 if self.fmus[component].fmi3 else slave.getInteger)([v.valueReference])[0]
        if v.type == "Boolean":
            return slave.getBoolean([v.valueReference])[0]
        raise TypeError(f"{component}.{name}: unsupported type {v.type}")

    def run(self, stop_time: float, step: float, start: dict, observe) -> None:
        """One experiment from t = 0 over round(stop_time / step) steps of `step`: fmi2Reset (from
        the second run on), the system's start values then `start` ({"component.variable":
        value}) on top, initialization with the connections propagated once per component (so
        outputs computed from inputs, the controller's first sample, see the initial state), then
        at every communication point k (t = k step): propagate, `observe(k, t)`, step every FMU.
        A False from `observe` ends the run early. Ends with fmi2Terminate; an FMU call that is
        not fmi2OK raises fmpy's FMICallException. FMI 3.0 instances get the same calls in their
        3.0 form (fmi3EnterInitializationMode with the start and stop time, fmi3Reset, ...); a
        3.0 fmi3DoStep that asks to terminate or returns early raises RuntimeError."""
        n = int(round(stop_time / step))
        if self.runs:
            for slave in self.slaves.values():
                slave.reset()
        self.runs += 1
        for qualified, value in {**self.start, **start}.items():
            self.set(qualified, value)
        for name, slave in self.slaves.items():
            if not self.fmus[name].fmi3:
                slave.setupExperiment(startTime=0.0, stopTime=n * step)
        for name, slave in self.slaves.items():
            if self.fmus[name].fmi3:
                # FMI 3.0 has no fmi3SetupExperiment: the experiment comes with this call.
                slave.enterInitializationMode(startTime=0.0, stopTime=n * step)
            else:
                slave.enterInitializationMode()
        # In Initialization Mode clocked variables are set and read whatever the clocks (FMI 3.0).
        self._ticking = {name: bool(fmu.clocks) for name, fmu in self.fmus.items()}
        self._in_event_mode = {name: False for name in self.fmus}
        for _ in self.slaves:
            self.propagate()
        self._read_clocks(step)
        self._ticking = {name: False for name in self.fmus}
        for name, slave in self.slaves.items():
            slave.exitInitializationMode()
            self._in_event_mode[name] = bool(self.fmus[name].clocks)
        self._held.clear()
        for k in range(n + 1):
            t = k * step
            self._tick(k, step)
            self.propagate()
            if not observe(k, t) or k == n:
                break
            self._end_events()
            for name, slave in self.slaves.items():
                done = slave.doStep(currentCommunicationPoint=t, communicationStepSize=step)
                if self.fmus[name].fmi3:
                    _check_fmi3_step(name, t, step, done)
        self._end_events()
        for slave in self.slaves.values():
            slave.terminate()

    def _read_clocks(self, step: float) -> None:
        """In Initialization Mode: each clock's interval and shift (fmi3GetIntervalDecimal,
        fmi3GetShiftDecimal), whose ticks must be communication points."""
        self._ticks.clear()
        for name, fmu in self.fmus.items():
            if not fmu.clocks:
                continue
            slave = self.slaves[name]
            vrs = (ctypes.c_uint * len(fmu.clocks))(*[c.valueReference for c in fmu.clocks])
            intervals = (ctypes.c_double * len(fmu.clocks))()
            qualifiers = (ctypes.c_int * len(fmu.clocks))()
            shifts = (ctypes.c_double * len(fmu.clocks))()
            slave.getIntervalDecimal(vrs, intervals, qualifiers)
            slave.fmi3GetShiftDecimal(slave.component, vrs, len(fmu.clocks), shifts)
            ticks = []
            for c, h, s in zip(fmu.clocks, intervals, shifts):
                for what, x in (("interval", h), ("shift", s)):
                    if abs(x / step - round(x / step)) > 1e-9 * max(1.0, x / step):
                        raise ValueError(f"{name}: the {what} of clock '{c.name}', {x} s, is no multiple of the communication step {step} s: its ticks would fall between communication points")
                ticks.append((c.valueReference, int(round(s / step)), int(round(h / step))))
            self._ticks[name] = ticks

    def _tick(self, k: int, step: float) -> None:
        """At communication point k: every clocked instance whose clocks tick enters Event Mode
        (after initialization it is there) and activates them."""
        for name, ticks in self._ticks.items():
            due = [vr for vr, s, h in ticks if k >= s and (k - s) % h == 0]
            if not due:
                continue
            slave = self.slaves[name]
            if not self._in_event_mode[name]:
                slave.enterEventMode()
                self._in_event_mode[name] = True
            slave.setClock(due, [True] * len(due))
            self._ticking[name] = True

    def _end_events(self) -> None:
        """Every instance in Event Mode: fmi3UpdateDiscreteStates until done (it deactivates the
        clocks), then fmi3EnterStepMode."""
        for name, in_event in self._in_event_mode.items():
            if not in_event:
                continue
            slave = self.slaves[name]
            while True:
                need, terminate, *_ = slave.updateDiscreteStates()
                if terminate:
                    raise RuntimeError(f"{name}: fmi3UpdateDiscreteStates asked to terminate the simulation")
                if not need:
                    break
            slave.enterStepMode()
            self._in_event_mode[name] = False
            self._ticking[name] = False

    def close(self) -> None:
        for slave in self.slaves.values():
            try:
                slave.freeInstance()
            except Exception:  # freeing is best effort; an instance may be in a broken state
                pass
        self.slaves.clear()
        for fmu in self._own.values():
            fmu.close()


def _fmi3_logger(callbacks, instance: str):
    """FMU3Slave's logMessage for `instance` from the loop's `callbacks` (None: fmpy's default)."""
    if callbacks is None:
        return None
    if not hasattr(callbacks, "fmi3_logger"):
        raise TypeError(f"{instance}: an FMI 3.0 instance logs through a cosim.fmu_log.LogRoute, not {type(callbacks).__name__}")
    return callbacks.fmi3_logger(instance)


def _check_fmi3_step(instance: str, t: float, step: float, result) -> None:
    """fmpy's FMU3Slave.doStep returns (eventHandlingNeeded, terminateSimulation, earlyReturn,
    lastSuccessfulTime); the master uses neither event mode nor early return."""
    _event, terminate, early_return, last = result
    if terminate:
        raise RuntimeError(f"{instance}: fmi3DoStep({t}, {step}) asked to terminate the simulation at t = {last}")
    if early_return:
        raise RuntimeError(f"{instance}: fmi3DoStep({t}, {step}) returned early at t = {last} (early return was not allowed)")


def simulate(system: System, stop_time: float, step: float, record: dict[str, list[str]], order: str = "gauss-seidel") -> dict:
    """Runs `system` (fresh instances) from t = 0 to `stop_time` with communication step `step`,
    each communication point evaluated in `order` (see `Loop`).

    `record` names, per component, the variables to record at every communication point.
    Returns {"time": array, "<component>.<variable>": array, ...}.
    """
    n = int(round(stop_time / step))
    keys = [(c, v) for c, vs in record.items() for v in vs]
    data = np.empty((n + 1, len(keys)))
    loop = Loop(system, order=order)
    try:

        def observe(k, _t):
            data[k] = [loop.get(c, v) for c, v in keys]
            return True

        loop.run(stop_time, step, {}, observe)
    finally:
        loop.close()
    out = {"time": np.arange(n + 1) * step}
    for i, (c, v) in enumerate(keys):
        out[f"{c}.{v}"] = data[:, i]
    return out
