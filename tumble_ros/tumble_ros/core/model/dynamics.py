"""
Euler-Liouville equations of a rigid asteroid under the Sun's gravity-gradient torque.

State vector ``y`` (all in body principal axes, time in years):

* ``y[0:3]`` = angular velocity (wx, wy, wz) [rad/yr], body frame;
* ``y[3:]``  = attitude, in one of two representations (see ``ATTITUDE_MODELS``):

  - ``"quaternion"``: unit quaternion (q0, q1, q2, q3), scalar first, body -> orbital
    frame, kinematics dq/dt = 1/2 q * (0, w). No singularity.
  - ``"euler"``: the paper's Euler angles (phi, psi, theta) with the kinematic equations
    of the paper (eq 15), singular at theta = 0, pi.

Dynamics (Euler's equations, paper eq 14 with the third line corrected,
docs/paper.md correction 1)::

    Ix dwx/dt = (Iy - Iz) wy wz + Mx
    Iy dwy/dt = (Iz - Ix) wz wx + My
    Iz dwz/dt = (Ix - Iy) wx wy + Mz

with M the total torque (``kernels.body_torque``): the gravity gradient (paper eq 12,
``torques.gravity_gradient``), any impact torque active on the current integration segment
and the scenario's extra torques (``torques.TorqueComponent``). Right-hand sides are built
for one segment at a time with the impact torque held constant (see ``propagator``), and
are written on plain floats: they are the integration's hot path.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, Callable, Sequence

import numpy as np

from tumble_ros.core import kernels
from tumble_ros.core.array_types import ArrayLike, FloatArray, Vector3
from tumble_ros.core.compiling.jit import python_source
from tumble_ros.core.kernels import samples
from tumble_ros.core.model.rotation import (euler_to_matrix, euler_to_quaternion, matrix_to_euler,
                                            quaternion_to_matrix)
from tumble_ros.core.torques import (extra_torque_arrays, tidal_potential_coefficient,
                                     TorqueComponent)

__all__ = [
    'AttitudeModel',
    'ATTITUDE_MODELS',
    'Rhs',
    'kinetic_energy',
    'angular_momentum_orbital',
    'jacobi_integral',
]

Rhs = Callable[[float, np.ndarray], np.ndarray]
_ZERO: Vector3 = (0.0, 0.0, 0.0)
#: The kernels' ``extra`` argument (:func:`~.torques.extra_torque_arrays`).
ExtraTorques = tuple[tuple[Callable[..., Any], ...], FloatArray] | None


def _segment_arrays(inertia: ArrayLike, orbit_rate: float, torque_body: ArrayLike,
                    torque_orbital: ArrayLike, extra_torques: Sequence[TorqueComponent],
                    ) -> tuple[FloatArray, ExtraTorques]:
    """Return the kernels' problem array and ``extra`` argument of one segment."""
    return (kernels.problem_array(np.asarray(inertia, dtype=float), orbit_rate,
                                  tuple(np.asarray(torque_body, dtype=float)),
                                  tuple(np.asarray(torque_orbital, dtype=float))),
            extra_torque_arrays(extra_torques))


def _make_quaternion_rhs(inertia: ArrayLike, orbit_rate: float, torque_body: ArrayLike = _ZERO,
                         torque_orbital: ArrayLike = _ZERO,
                         extra_torques: Sequence[TorqueComponent] = ()) -> Rhs:
    """
    Return f(t, y) for the quaternion attitude: the kernels' right-hand side (one implementation).

    ``kernels.rhs`` (compiled, or plain Python without numba) is what the compiled loops run;
    the reference steppers call it through this closure, one evaluation at a time.
    """
    p, extra = _segment_arrays(inertia, orbit_rate, torque_body, torque_orbital, extra_torques)
    st = np.zeros(2 * kernels.N)
    evaluate, n = kernels.rhs_called, kernels.N

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        st[:n] = y
        evaluate(p, extra, float(t), st, 0, n)
        return st[n:].copy()

    return rhs


def _make_euler_rhs(inertia: ArrayLike, orbit_rate: float, torque_body: ArrayLike = _ZERO,
                    torque_orbital: ArrayLike = _ZERO,
                    extra_torques: Sequence[TorqueComponent] = ()) -> Rhs:
    """
    Return f(t, y) for the paper's Euler angles: eq 15 kinematics, the kernels' torque.

    The torque is ``kernels.body_torque`` (the one total torque) at the attitude's quaternion;
    Euler's equations as in ``kernels.rhs``.
    """
    p, extra = _segment_arrays(inertia, orbit_rate, torque_body, torque_orbital, extra_torques)
    torque = kernels.body_torque
    ex, ey, ez = p[kernels.PR.EULER:kernels.PR.EULER + 3].tolist()
    jx, jy, jz = p[kernels.PR.INV_INERTIA:kernels.PR.INV_INERTIA + 3].tolist()
    sin, cos, array = math.sin, math.cos, np.array

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        wx, wy, wz, phi, psi, theta = y.tolist()
        tx, ty, tz = torque(p, extra, float(t), *euler_to_quaternion(phi, psi, theta).tolist())
        cp, sp = cos(psi), sin(psi)
        ct, st = cos(theta), sin(theta)
        # Paper eq 15 (correct as printed).
        w_perp = wx * sp + wy * cp
        return array((ex * wy * wz + tx * jx, ey * wz * wx + ty * jy, ez * wx * wy + tz * jz,
                      w_perp / st, wz - w_perp * ct / st, wx * cp - wy * sp))

    return rhs


@dataclass(frozen=True)
class AttitudeModel:
    """
    One way of carrying the attitude in the state vector.

    Attributes
    ----------
    name : registry key.
    size : number of attitude components in the state vector.
    from_euler : paper's Euler angles (phi, psi, theta) -> attitude components.
    to_matrix : attitude components -> C (body -> orbital) 3x3 matrix.
    make_rhs : (inertia, orbit_rate, torque_body, torque_orbital, extra_torques) -> f(t, y).
    singular : attitude components -> True where this representation breaks down.

    """

    name: str
    size: int
    from_euler: Callable[[float, float, float], np.ndarray]
    to_matrix: Callable[[np.ndarray], np.ndarray]
    make_rhs: Callable[..., Rhs]
    singular: Callable[[Sequence[float] | np.ndarray], bool]

    def to_euler(self, attitude: np.ndarray) -> tuple[float, float, float]:
        """Paper's Euler angles (phi, psi, theta), phi and psi wrapped to (-pi, pi]."""
        return matrix_to_euler(self.to_matrix(attitude).T)


ATTITUDE_MODELS: dict[str, AttitudeModel] = {
    'quaternion': AttitudeModel(
        name='quaternion',
        size=4,
        from_euler=euler_to_quaternion,
        to_matrix=quaternion_to_matrix,
        make_rhs=_make_quaternion_rhs,
        singular=lambda a: False,
    ),
    'euler': AttitudeModel(
        name='euler',
        size=3,
        from_euler=lambda phi, psi, theta: np.array([phi, psi, theta], dtype=float),
        to_matrix=lambda a: euler_to_matrix(a[0], a[1], a[2]).T,
        make_rhs=_make_euler_rhs,
        # eq 15 divides by sin(theta); below this the attitude is numerically meaningless.
        singular=lambda a: abs(math.sin(a[2])) < 1e-9,
    ),
}


def kinetic_energy(omega: ArrayLike, inertia: ArrayLike) -> FloatArray:
    """Rotational kinetic energy 1/2 w.I.w for (3,) or (n, 3) body rates."""
    w = np.asarray(omega, dtype=float)
    energy: FloatArray = 0.5 * _sum3(w * w * np.asarray(inertia, dtype=float))
    return energy


def _sum3(v: FloatArray) -> FloatArray:
    """
    Sum of v's last axis (3 components) in numpy's order, (v0 + v1) + v2: np.sum's bits.

    Written out: ``np.sum(..., axis=-1)`` over 3 components costs a reduction loop's set-up
    per sample (~30 ns).
    """
    total: FloatArray = v[..., 0] + v[..., 1] + v[..., 2]
    return total


def angular_momentum_orbital(omega: ArrayLike, c_body_to_orbital: np.ndarray,
                             inertia: ArrayLike) -> FloatArray:
    """
    Angular momentum L = C (I w) in orbital-frame components.

    Shapes: omega (3,) with a (3, 3) matrix, or (n, 3) with (n, 3, 3).
    """
    h = np.asarray(omega, dtype=float) * np.asarray(inertia, dtype=float)
    momentum: FloatArray = np.einsum('...ij,...j->...i', c_body_to_orbital, h)
    return momentum


def jacobi_integral(t: ArrayLike, omega: ArrayLike, c_body_to_orbital: ArrayLike,
                    inertia: ArrayLike, orbit_rate: float) -> FloatArray:
    """
    Jacobi integral of the circular-orbit problem (conserved without impacts).

    In the frame turning with the Sun line (angular velocity Omega = -ws Z') the tidal
    potential is time independent, so H = T + V - Omega.L is conserved::

        J = 1/2 w.I.w + 3/2 ws^2 u.I.u + ws (I w).z'

    with u the Sun direction and z' the orbit normal, both in body axes
    (derivation in docs/physics.md). Inputs may be single samples or arrays of n samples:
    t (n,), omega (n, 3), c_body_to_orbital (n, 3, 3).
    """
    t = np.asarray(t, dtype=float)
    c = np.asarray(c_body_to_orbital, dtype=float)
    i = np.asarray(inertia, dtype=float)
    w = np.asarray(omega, dtype=float)
    # the formula is kernels.samples.jacobi_sample's, here on arrays (an ensemble's compiled
    # post-processing evaluates it one sample at a time: the same bits)
    on_arrays: Callable[..., Any] = python_source(samples.jacobi_sample)
    jacobi: FloatArray = on_arrays(
        np.sin(orbit_rate * t), np.cos(orbit_rate * t), w[..., 0], w[..., 1], w[..., 2],
        c[..., 0, 0], c[..., 0, 1], c[..., 0, 2], c[..., 1, 0], c[..., 1, 1], c[..., 1, 2],
        c[..., 2, 0], c[..., 2, 1], c[..., 2, 2], i[0], i[1], i[2], orbit_rate,
        tidal_potential_coefficient(orbit_rate))
    return jacobi
