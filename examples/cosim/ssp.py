"""Runs the project's .ssp files in the two SSP importers: fmpy.ssp and libcosim (libcosimpy)."""

from __future__ import annotations

import numpy as np


def ssp_start_values(ssp_path: str):
    """The ParameterBindings of every component, as one fmpy ParameterSet named
    "<component>.<variable>" (fmpy's simulate_ssp applies only the set it is given, and
    converts Boolean literals wrongly from text, so the values are typed here)."""
    from fmpy.ssp.ssd import Parameter, ParameterSet, find_components, read_ssd

    convert = {"Real": float, "Integer": int, "Boolean": lambda s: s.strip().lower() in ("true", "1")}
    result = ParameterSet(name="bindings")
    for c in find_components(read_ssd(ssp_path).system):
        for binding in c.parameterBindings:
            for pset in binding.parameterValues:
                for p in pset.parameters:
                    result.parameters.append(Parameter(name=f"{c.name}.{p.name}", type=p.type, value=convert[p.type](p.value)))
    return result


def ssp_connections(ssp_path: str) -> set[tuple[str, str, str, str]]:
    from fmpy.ssp.ssd import read_ssd

    system = read_ssd(ssp_path).system
    return {(k.startElement, k.startConnector, k.endElement, k.endConnector) for k in system.connections}


def simulate_fmpy_ssp(ssp_path: str, stop_time: float, step: float, variables: list[str]) -> dict:
    """fmpy.ssp.simulate_ssp. Its rows are stamped with the time at the START of each step but
    hold the values after it, so the times are shifted by one step here; its connectors start at
    0 (no propagation in initialization mode)."""
    from fmpy.ssp.simulation import simulate_ssp

    n = int(round(stop_time / step))
    r = simulate_ssp(ssp_path, stop_time=n * step, step_size=step, parameter_set=ssp_start_values(ssp_path))
    r = r[:n]
    out = {"time": (np.arange(len(r)) + 1) * step}
    for v in variables:
        out[v] = np.asarray(r[v], float)
    return out


def simulate_libcosim(ssp_path: str, stop_time: float, step: float, variables: list[str], start: dict) -> dict:
    """libcosim's fixed-step algorithm on the .ssp file, which it applies itself (the Pendulum's
    initial state is the parameters alpha1_0..omega2_0); `start` ({"component.variable": value})
    overrides Real values through real_initial_value."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)
    ns = int(round(step * 1e9))
    n = int(round(stop_time / step))
    ex = CosimExecution.from_ssp_file(ssp_path, step_size=ns)
    refs = {}

    def ref(name):
        component, var = name.split(".", 1)
        idx = ex.slave_index_from_instance_name(component)
        table = {v.name.decode(): v.reference for v in ex.slave_variables(idx)}
        return idx, table[var]

    for name, value in start.items():
        idx, vr = ref(name)
        if not ex.real_initial_value(idx, vr, float(value)):
            raise RuntimeError(f"libcosim refused the initial value of {name}")
    observer = CosimObserver.create_time_series(buffer_size=n + 10)
    ex.add_observer(observer)
    for v in variables:
        refs[v] = ref(v)
        observer.start_time_series(refs[v][0], refs[v][1], CosimVariableType.REAL)
    ex.simulate_until(n * ns)
    out = {}
    for v in variables:
        times, _, values = observer.time_series_real_samples(refs[v][0], refs[v][1], 0, n + 1)
        out["time"] = np.asarray(times, float) * 1e-9
        out[v] = np.asarray(values, float)
    return out
