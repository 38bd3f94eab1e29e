"""Collecting the FMUs' log messages per instance group, through fmpy's native logger proxy
(FMI 2.0) or fmpy's fmi3LogMessageCallback (FMI 3.0).

The FMUs log printf-style (format "%s", the text as argument); fmpy's `addLoggerProxy` formats
the message in C before calling Python. But the proxy keeps ONE Python target per process: the
logger registered last receives the messages of every instance, whichever callbacks it was
created with (measured: two instances with two loggers, both messages reached the second).
So one dispatcher is registered here, and each message is routed by the componentEnvironment
its instance was created with, which the proxy passes through unchanged.
"""

import ctypes
import itertools
import threading

from fmpy.fmi2 import defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.logging import addLoggerProxy

_sinks: dict = {}
_keys = itertools.count(1)
_lock = threading.Lock()


def _dispatch(environment, instance, status, category, message):
    sink = _sinks.get(environment or 0)
    if sink is not None:
        sink(
            instance.decode(errors="replace") if instance else "",
            status,
            category.decode(errors="replace") if category else "",
            message.decode(errors="replace") if message else "",
        )


# Module-level, so the ctypes callback outlives every instance that may call it.
_LOGGER = fmi2CallbackLoggerTYPE(_dispatch)


class LogRoute:
    """fmi2CallbackFunctions (`.callbacks`, to pass to FMU2Slave.instantiate) whose messages go to
    `sink(instance, status, category, text)`. Call `close()` when its instances are freed.

    FMI 3.0 needs no proxy (fmi3LogMessageCallback takes the message itself, not a format):
    `fmi3_logger(instance)` is a logMessage for FMU3Slave.instantiate that calls the same sink,
    with the instance's name (the 3.0 callback does not pass one)."""

    def __init__(self, sink):
        with _lock:
            self.key = next(_keys)
            _sinks[self.key] = sink
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = _LOGGER
        self.callbacks.allocateMemory = defaultCallbacks.allocateMemory
        self.callbacks.freeMemory = defaultCallbacks.freeMemory
        self.callbacks.componentEnvironment = ctypes.c_void_p(self.key)
        addLoggerProxy(ctypes.byref(self.callbacks))

    def fmi3_logger(self, instance: str):
        def log_message(_environment, status, category, message):
            sink = _sinks.get(self.key)
            if sink is not None:
                sink(
                    instance,
                    status,
                    category.decode(errors="replace") if category else "",
                    message.decode(errors="replace") if message else "",
                )

        return log_message

    def close(self):
        with _lock:
            _sinks.pop(self.key, None)
