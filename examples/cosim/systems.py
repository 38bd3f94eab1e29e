"""The paper's two composed systems, read from the SSP files `fmu-build` writes, and the linear
closed loop they are checked against.

The systems are described once, as data (`holonomic/systems.toml`): `fmu-build` writes them as
`target/fmu/PendulumLQR.ssp` and `target/fmu/PendulumMotors.ssp`. This module reads the
`SystemStructure.ssd` inside them (components with their FMU, parameter bindings with their
types and values, connections) and writes none of those values itself:

- PendulumLQR: Controller.M1/M2 drive Pendulum.M1/M2 (the paper's Figure 7 setting);
- PendulumMotors: Controller.U1/U2 -> DCMotor.U, Pendulum.omega_i -> DCMotor.omega,
  DCMotor.tau -> Pendulum.M_i (Figure 8), with the demo motor (200:1 gearbox, realistic friction;
  docs/composition.md).
"""

from __future__ import annotations

import dataclasses
import pathlib
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import scipy.linalg

from .master import Component, Connection, System

_NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
}

#: SSP parameter types -> Python values (SSP Boolean literals are "true"/"false").
_VALUE = {
    "Real": float,
    "Integer": int,
    "Boolean": lambda text: {"true": True, "false": False}[text.strip().lower()],
}


def ssp_path(name: str, fmu: str | pathlib.Path) -> pathlib.Path:
    """Where fmu-build writes system `name`: next to the FMUs (target/fmu/<name>.ssp). For an FMI
    3.0 FMU (target/fmu/fmi3/<id>.fmu) without an SSP file beside it, the one of the 2.0 FMUs in
    the folder above: the system (components, start values, connections) is the same for both
    versions, and `bind` puts the given FMU files in it."""
    here = pathlib.Path(fmu).resolve().parent
    path = here / f"{name}.ssp"
    if not path.exists() and here.name == "fmi3":
        return here.parent / f"{name}.ssp"
    return path


def read_ssp(path: str | pathlib.Path) -> System:
    """The system in the SSP file's SystemStructure.ssd. Each component's `fmu` is the model
    identifier of its FMU (the stem of its `source`, e.g. "resources/Pendulum.fmu" ->
    "Pendulum"); `bind` replaces it by an FMU file. Start values are the typed values of the
    component's ParameterBindings."""
    path = pathlib.Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path} is missing: run `cargo run --release -p fmu-build` (it writes the SSP files)")
    with zipfile.ZipFile(path) as z:
        root = ET.fromstring(z.read("SystemStructure.ssd"))
    system = root.find("ssd:System", _NS)
    if system is None:
        raise ValueError(f"{path}: SystemStructure.ssd has no ssd:System")
    components = []
    for c in system.iterfind("ssd:Elements/ssd:Component", _NS):
        start = {}
        for p in c.iterfind("ssd:ParameterBindings/ssd:ParameterBinding/ssd:ParameterValues/ssv:ParameterSet/ssv:Parameters/ssv:Parameter", _NS):
            typed = [e for e in p if e.tag.split("}")[-1] in _VALUE]
            if len(typed) != 1:
                raise ValueError(f"{path}: {c.get('name')}.{p.get('name')}: expected one ssv:Real, ssv:Integer or ssv:Boolean")
            kind = typed[0].tag.split("}")[-1]
            start[p.get("name")] = _VALUE[kind](typed[0].get("value"))
        components.append(Component(c.get("name"), pathlib.PurePosixPath(c.get("source")).stem, start))
    connections = tuple(
        Connection(k.get("startElement"), k.get("startConnector"), k.get("endElement"), k.get("endConnector"))
        for k in system.iterfind("ssd:Connections/ssd:Connection", _NS)
    )
    return System(system.get("name"), tuple(components), connections)


def bind(system: System, fmus: dict[str, str], overrides: dict | None = None) -> System:
    """`system` (as `read_ssp` returns it) with each component's model identifier replaced by
    its FMU file `fmus[identifier]`, and `overrides` ({"component.variable": value}) applied on
    top of the SSD's start values (None values are ignored)."""
    overrides = {k: v for k, v in (overrides or {}).items() if v is not None}
    names = {c.name for c in system.components}
    for key in overrides:
        if key.partition(".")[0] not in names:
            raise KeyError(f"'{key}': system {system.name} has no component '{key.partition('.')[0]}' (has {sorted(names)})")
    components = []
    for c in system.components:
        if c.fmu not in fmus:
            raise KeyError(f"{system.name}: component '{c.name}' needs the {c.fmu} FMU, given only {sorted(fmus)}")
        start = dict(c.start)
        start.update({k.partition(".")[2]: v for k, v in overrides.items() if k.partition(".")[0] == c.name})
        components.append(dataclasses.replace(c, fmu=fmus[c.fmu], start=start))
    return dataclasses.replace(system, components=tuple(components))


def plant_and_controller(pendulum_fmu: str, controller_fmu: str, alpha1=None, alpha2=None, mode=None, ssp=None) -> System:
    """PendulumLQR from `ssp` (default: PendulumLQR.ssp next to `pendulum_fmu`), with the given
    FMU files; alpha1, alpha2 (initial angles, rad) and mode (controller law) override the SSD."""
    return bind(
        read_ssp(ssp or ssp_path("PendulumLQR", pendulum_fmu)),
        {"Pendulum": pendulum_fmu, "Controller": controller_fmu},
        {"pendulum.alpha1_0": alpha1, "pendulum.alpha2_0": alpha2, "controller.mode": mode},
    )


def plant_motors_controller(
    pendulum_fmu: str, controller_fmu: str, motor_fmu: str, alpha1=None, alpha2=None, mode=None, ssp=None
) -> System:
    """PendulumMotors from `ssp` (default: PendulumMotors.ssp next to `pendulum_fmu`), with the
    given FMU files; alpha1, alpha2 (rad) and mode override the SSD."""
    return bind(
        read_ssp(ssp or ssp_path("PendulumMotors", pendulum_fmu)),
        {"Pendulum": pendulum_fmu, "Controller": controller_fmu, "DCMotor": motor_fmu},
        {"pendulum.alpha1_0": alpha1, "pendulum.alpha2_0": alpha2, "controller.mode": mode},
    )


def closed_loop_matrices(k: np.ndarray, m1=0.5, m2=0.5, l1=1.0, l2=1.0, g=9.81):
    """A and B of the paper's linearization (12), from its mass matrix and gravity terms, and
    A - B K. Written independently of the Rust model (the tests compare the two)."""
    mass = np.array([[(m1 + m2) * l1**2 / 3, m2 * l1 * l2 / 3], [m2 * l1 * l2 / 3, m2 * l2**2 / 3]])
    stiffness = np.diag([m1 * g * l1 / 2 + m2 * g * l1, m2 * g * l2 / 2])
    minv = np.linalg.inv(mass)
    a = np.zeros((4, 4))
    b = np.zeros((4, 2))
    a[0, 1] = a[2, 3] = 1.0
    acc = minv @ stiffness
    a[1, 0], a[1, 2], a[3, 0], a[3, 2] = acc[0, 0], acc[0, 1], acc[1, 0], acc[1, 1]
    b[1], b[3] = minv[0], minv[1]
    return a, b, a - b @ k


def linear_response(acl: np.ndarray, x0, times) -> np.ndarray:
    """x(t) = exp(Acl t) x0 at the given times, shape (len(times), 4)."""
    return np.array([scipy.linalg.expm(acl * t) @ np.asarray(x0, float) for t in times])
