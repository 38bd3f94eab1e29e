"""A fixed-step co-simulation master for FMI 2.0 co-simulation FMUs, on fmpy's FMU2Slave.

Every FMU of this project has outputs that do not depend directly on its inputs at the same
instant (ModelStructure dependencies=""), so a Jacobi master is exact about causality: at each
communication point read every output, write every connected input, then step every FMU over the
same interval. In initialization mode the connections are propagated once per component, so that
outputs computed from inputs (the controller's first sample) see the initial state.
"""

from __future__ import annotations

import dataclasses
import shutil

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave


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


class _Instance:
    def __init__(self, component: Component):
        self.md = read_model_description(component.fmu)
        self.dir = extract(component.fmu)
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.slave = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=self.dir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=component.name,
        )

    def var(self, name: str):
        try:
            return self.vars[name]
        except KeyError:
            raise KeyError(f"{self.md.modelName} has no variable '{name}'") from None

    def set(self, name: str, value) -> None:
        v = self.var(name)
        if v.type == "Real":
            self.slave.setReal([v.valueReference], [float(value)])
        elif v.type == "Integer":
            self.slave.setInteger([v.valueReference], [int(value)])
        elif v.type == "Boolean":
            self.slave.setBoolean([v.valueReference], [bool(value)])
        else:
            raise TypeError(f"{name}: unsupported type {v.type}")

    def get(self, name: str) -> float:
        v = self.var(name)
        if v.type == "Real":
            return self.slave.getReal([v.valueReference])[0]
        if v.type == "Integer":
            return self.slave.getInteger([v.valueReference])[0]
        return self.slave.getBoolean([v.valueReference])[0]

    def close(self) -> None:
        self.slave.terminate()
        self.slave.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)


def simulate(system: System, stop_time: float, step: float, record: dict[str, list[str]]) -> dict:
    """Runs `system` from t = 0 to `stop_time` with communication step `step`.

    `record` names, per component, the variables to record at every communication point.
    Returns {"time": array, "<component>.<variable>": array, ...}.
    """
    n = int(round(stop_time / step))
    stop_time = n * step
    instances = {c.name: _Instance(c) for c in system.components}
    try:
        for c in system.components:
            inst = instances[c.name]
            inst.slave.instantiate()
            for name, value in c.start.items():
                inst.set(name, value)
            inst.slave.setupExperiment(startTime=0.0, stopTime=stop_time)
        for inst in instances.values():
            inst.slave.enterInitializationMode()

        def propagate():
            for k in system.connections:
                instances[k.target].set(k.target_var, instances[k.source].get(k.source_var))

        for _ in system.components:
            propagate()
        for inst in instances.values():
            inst.slave.exitInitializationMode()

        keys = [(c, v) for c, vs in record.items() for v in vs]
        out = {"time": np.arange(n + 1) * step}
        data = np.empty((n + 1, len(keys)))
        for k in range(n + 1):
            propagate()
            data[k] = [instances[c].get(v) for c, v in keys]
            if k == n:
                break
            t = k * step
            for inst in instances.values():
                # fmpy raises an exception (with the FMU's status) when a step is not fmi2OK.
                inst.slave.doStep(currentCommunicationPoint=t, communicationStepSize=step)
        for i, (c, v) in enumerate(keys):
            out[f"{c}.{v}"] = data[:, i]
        return out
    finally:
        for inst in instances.values():
            try:
                inst.close()
            except Exception:  # an FMU that failed to instantiate has nothing to free
                pass
