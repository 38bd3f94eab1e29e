"""An independent implementation of the paper's plant, equations (6)-(7), for reference solutions.

Written from the paper, not from the Rust code: the 2x2 mass-matrix system is solved with numpy.
State x = (alpha1, omega1, alpha2, omega2) [rad, rad/s], absolute angles from the upward vertical;
inputs M1, M2 [N.m] are the generalized torques of (6) and (7).

J1, J2 [kg.m2] (default 0, the paper's model) are extra inertias at the joints, e.g. geared motor
rotors n^2 J: each adds J_i omega_i^2/2 to the kinetic energy, so Lagrange's equations gain
J1 d(omega1)/dt in (6) and J2 d(omega2)/dt in (7), i.e. J1 on the (1,1) and J2 on the (2,2) entry
of the mass matrix.
"""

import numpy as np
from scipy.integrate import solve_ivp

PAPER = dict(m1=0.5, m2=0.5, l1=1.0, l2=1.0, g=9.81)


def rhs(x, M1=0.0, M2=0.0, m1=0.5, m2=0.5, l1=1.0, l2=1.0, g=9.81, J1=0.0, J2=0.0):
    a1, w1, a2, w2 = x
    c, s = np.cos(a1 - a2), np.sin(a1 - a2)
    mass = np.array(
        [[(m1 + m2) * l1**2 / 3 + J1, m2 * l1 * l2 * c / 3], [m2 * l1 * l2 * c / 3, m2 * l2**2 / 3 + J2]]
    )
    # eq. (6): ... - 1/3 m2 l1 l2 w2 s (w1 - w2) + 1/3 m2 l1 l2 w1 w2 s - (m1 g l1/2 + m2 g l1) sin a1 = M1
    v6 = -m2 * l1 * l2 * w2 * s * (w1 - w2) / 3 + m2 * l1 * l2 * w1 * w2 * s / 3
    # eq. (7): ... - 1/3 m2 l1 l2 w1 s (w1 - w2) - 1/3 m2 l1 l2 w1 w2 s - m2 g l2/2 sin a2 = M2
    v7 = -m2 * l1 * l2 * w1 * s * (w1 - w2) / 3 - m2 * l1 * l2 * w1 * w2 * s / 3
    r = np.array(
        [M1 - v6 + (m1 * g * l1 / 2 + m2 * g * l1) * np.sin(a1), M2 - v7 + m2 * g * l2 / 2 * np.sin(a2)]
    )
    acc = np.linalg.solve(mass, r)
    return np.array([w1, acc[0], w2, acc[1]])


def energy(x, m1=0.5, m2=0.5, l1=1.0, l2=1.0, g=9.81, J1=0.0, J2=0.0):
    """Equations (2)-(5), plus the joints' extra inertias J1 omega1^2/2 + J2 omega2^2/2."""
    a1, w1, a2, w2 = x
    ek = (m1 + m2) * l1**2 * w1**2 / 6 + m2 * l2**2 * w2**2 / 6 + m2 * l1 * l2 * w1 * w2 * np.cos(a1 - a2) / 3
    ep = m1 * g * l1 / 2 * np.cos(a1) + m2 * g * (l1 * np.cos(a1) + l2 / 2 * np.cos(a2))
    return ek + ep + (J1 * w1**2 + J2 * w2**2) / 2


def reference(x0, t_eval, M1=0.0, M2=0.0, rtol=1e-12, atol=1e-12, **params):
    """Tight-tolerance DOP853 solution of (6)-(7) with constant torques, at the times t_eval."""
    sol = solve_ivp(
        lambda t, x: rhs(x, M1, M2, **params),
        (t_eval[0], t_eval[-1]),
        np.asarray(x0, dtype=float),
        method="DOP853",
        t_eval=t_eval,
        rtol=rtol,
        atol=atol,
    )
    assert sol.success, sol.message
    return sol.y.T
