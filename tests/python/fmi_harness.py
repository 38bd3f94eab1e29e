"""Helpers for driving our FMUs through fmpy's FMU2Slave with a logger that keeps the messages."""

import shutil
from ctypes import byref

import fmpy
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.fmi2 import fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE
from fmpy.logging import addLoggerProxy
from ctypes import cdll, c_size_t, c_void_p
import ctypes.util

_libc = cdll.LoadLibrary(ctypes.util.find_library("c"))
_libc.calloc.restype = c_void_p
_libc.calloc.argtypes = [c_size_t, c_size_t]
_libc.free.argtypes = [c_void_p]


class LoggedSlave:
    """An FMU2Slave whose log messages are collected in `.messages` as (status, category, text)."""

    def __init__(self, path, name="instance", logging_on=False):
        self.md = fmpy.read_model_description(path)
        self.unzipdir = fmpy.extract(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages = []

        def log(env, instance, status, category, message):
            self.messages.append((status, category.decode(), message.decode()))

        # Kept on self: ctypes callbacks must outlive the instance.
        self._logger = fmi2CallbackLoggerTYPE(log)
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = self._logger
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_libc.calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(_libc.free)
        addLoggerProxy(byref(self._callbacks))  # formats the variadic message in C
        self.fmu = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=self.unzipdir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate(callbacks=self._callbacks, loggingOn=logging_on)

    def set(self, **values):
        self.fmu.setReal([self.vr[k] for k in values], list(values.values()))

    def get(self, *names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def errors(self):
        return [m for m in self.messages if m[0] >= 3]

    def close(self):
        self.fmu.freeInstance()
        shutil.rmtree(self.unzipdir, ignore_errors=True)
