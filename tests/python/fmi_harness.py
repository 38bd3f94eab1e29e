"""Helpers for driving our FMUs through fmpy's FMU2Slave and FMU3Slave with a logger that keeps the
messages."""

import shutil
import sys

import fmpy
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

from conftest import ROOT, fmu3

sys.path.insert(0, str(ROOT / "examples"))
from cosim.fmu_log import LogRoute  # noqa: E402


class LoggedSlave:
    """An FMU2Slave whose log messages are collected in `.messages` as (status, category, text)."""

    def __init__(self, path, name="instance", logging_on=False):
        self.md = fmpy.read_model_description(path)
        self.unzipdir = fmpy.extract(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages = []
        # Routed by componentEnvironment: fmpy's proxy alone would hand every instance's messages
        # to the logger registered last (examples/cosim/fmu_log.py).
        self._route = LogRoute(lambda _instance, status, category, text: self.messages.append((status, category, text)))
        self.fmu = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=self.unzipdir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate(callbacks=self._route.callbacks, loggingOn=logging_on)

    def set(self, **values):
        self.fmu.setReal([self.vr[k] for k in values], list(values.values()))

    def get(self, *names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def errors(self):
        return [m for m in self.messages if m[0] >= 3]

    def close(self):
        self.fmu.freeInstance()
        self._route.close()
        shutil.rmtree(self.unzipdir, ignore_errors=True)


def value_after_a_refused_set(path, name, value):
    """Sets the parameter `name` to `value` before initialization, which the FMU must refuse with an
    error naming `name`; returns `name`'s value after initialization (what the FMU kept)."""
    s = LoggedSlave(path)
    try:
        s.fmu.setupExperiment(startTime=0.0)
        with pytest.raises(FMICallException):
            s.set(**{name: value})
        assert any(f"'{name}'" in text for _, _, text in s.errors()), s.messages
        s.fmu.enterInitializationMode()
        s.fmu.exitInitializationMode()
        return s.get(name)[0]
    finally:
        s.close()


def fmu3_with_vrs(name):
    """The packaged FMI 3.0 FMU `name` of this workspace: (path, model description, {variable
    name: value reference})."""
    path = fmu3(name)
    md = fmpy.read_model_description(path)
    return path, md, {v.name: v.valueReference for v in md.modelVariables}


class EventModeSlave:
    """An FMU3Slave (`.f`) of `fmu` = fmu3_with_vrs(..) instantiated with Event Mode and logging on,
    its log messages kept in `.messages`, `params` set in Initialization Mode (float: Float64, bool:
    Boolean, int: Int32); in Event Mode after __init__."""

    def __init__(self, fmu, name, **params):
        path, md, self.vr = fmu
        self.messages = []
        self.f = FMU3Slave(guid=md.guid, unzipDirectory=fmpy.extract(path),
                           modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.f.instantiate(eventModeUsed=True, loggingOn=True,
                           logMessage=lambda *a: self.messages.append(a[-1].decode()))
        self.f.enterInitializationMode(startTime=0.0)
        for k, v in params.items():
            if isinstance(v, float):
                self.f.setFloat64([self.vr[k]], [v])
            elif isinstance(v, bool):
                self.f.setBoolean([self.vr[k]], [v])
            else:
                self.f.setInt32([self.vr[k]], [v])
        self.f.exitInitializationMode()

    def settle(self):
        """Updates the discrete states until they are stable (the end of an event's tick)."""
        while self.f.updateDiscreteStates()[0]:
            pass
