"""
The spin state of a tumbling body from one sample: mode, periods, pole.

For the torque-free motion through a state (omega, attitude) — what the body would do if the
torque stopped there — with the principal moments sorted I1 < I2 < I3 (I1: the long axis,
I3: the short axis), the rotational energy E = 1/2 w.Iw and the angular momentum L = |Iw|:

* the **mode**: the dynamical moment D = L^2 / (2E) lies in [I1, I3]; D > I2 is a short-axis
  mode (SAM: the body turns about an axis circling I3), D < I2 a long-axis mode (LAM: about
  I1), D = I2 the separatrix (Samarasinha & A'Hearn 1991, Icarus 93; Kaasalainen 2001, A&A 376);
* the **rotation period** P_psi: the period of w(t) in body axes (Jacobi elliptic functions of
  modulus k), P_psi = 4 K(k) sqrt(I1 I2 I3 / ((I3 - I2)(L^2 - 2E I1))) with
  k^2 = (I2 - I1)(2E I3 - L^2) / ((I3 - I2)(L^2 - 2E I1)) for a SAM, and the same with
  (I1 <-> I3) for a LAM (Landau & Lifshitz, Mechanics, sec. 37);
* the **precession period** P_phi: the mean period of the reference axis r (I3 in a SAM, I1 in
  a LAM) about L, 2 pi / <phi'>. The rate phi' = L (Ia wa^2 + Ib wb^2) / (Ia^2 wa^2 + Ib^2 wb^2)
  (a, b the two other axes) is, with Ia wa^2 + Ib wb^2 = 2E - Lr^2/Ir and
  Ia^2 wa^2 + Ib^2 wb^2 = L^2 - Lr^2, phi' = L/Ir + L (2E - L^2/Ir) / (L^2 - Lr^2). Along the
  polhode Lr^2 = Ir^2 wr0^2 dn^2(u, k) (wr0: wr where the intermediate component is 0), so
  L^2 - Lr^2 = A + B sn^2(u, k) with A = L^2 - Ir^2 wr0^2, B = k^2 Ir^2 wr0^2, whose inverse
  averages over a period of u to Pi(-B/A, k) / (A K(k)), Pi the complete elliptic integral of
  the third kind. Worked out, the state drops out of the characteristic n = -B/A and of
  (2E - L^2/Ir) / A:
  SAM: <phi'> = L/I3 + L (1/I1 - 1/I3) Pi(n, k) / K(k), n = -I3 (I2 - I1) / (I1 (I3 - I2));
  LAM: <phi'> = L/I1 - L (1/I1 - 1/I3) Pi(n, k) / K(k), n = -I1 (I3 - I2) / (I3 (I2 - I1))
  (nothing vanishes near a pure spin, where A and B both do), with
  Pi(n, k) / K(k) = 1 + n/3 R_J(0, 1 - k^2, 1, 1 - n) / R_F(0, 1 - k^2, 1) (Carlson; DLMF
  19.25.2). The same mean by quadrature of the Euler-Poinsot motion checks it
  (tests/test_core_spinstate.py);
* the **pole**: L's direction in the orbital frame (longitude from +X' towards +Y', latitude
  from the orbit plane).

For a symmetric body (I1 = I2 or I2 = I3) P_psi is the body-frame precession of w and P_phi =
2 pi I_sym / L. Units: w [rad/yr], periods [yr]; inertia normalised. Tested against
simulations (tests/test_core_spinstate.py).
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np
from scipy.special import ellipkm1, elliprf, elliprj

from tumble_ros.core.array_types import ArrayLike, Vector3
from tumble_ros.core.model.rotation import quaternion_to_matrix

__all__ = ['SpinState', 'spin_state', 'omega_for_periods']

_SEPARATRIX = 1e-12   # |D - I2| / I2 below this: the separatrix (infinite period)
#: The tumbling modes :func:`omega_for_periods` builds, and their names in its messages.
_MODE_NAMES = {'SAM': 'short-axis mode', 'LAM': 'long-axis mode'}


@dataclass(frozen=True)
class SpinState:
    """
    The torque-free spin state through one sample.

    Attributes
    ----------
    mode : 'SAM', 'LAM' or 'separatrix' (or 'principal' for a rotation about one axis).
    energy : rotational energy E = 1/2 w.Iw [I rad^2/yr^2].
    momentum : |L| = |Iw| [I rad/yr].
    dynamic_inertia : D = L^2 / 2E, between I1 and I3.
    rotation_period : P_psi [yr] (inf at the separatrix, the spin period for a principal
        rotation).
    precession_period : P_phi [yr] (the spin period for a principal rotation).
    pole : L's unit vector in the orbital frame (None without an attitude).
    pole_longitude, pole_latitude : [rad] (None without an attitude).

    """

    mode: str
    energy: float
    momentum: float
    dynamic_inertia: float
    rotation_period: float
    precession_period: float
    pole: tuple[float, float, float] | None = None
    pole_longitude: float | None = None
    pole_latitude: float | None = None


def spin_state(omega: ArrayLike, inertia: ArrayLike,
               quaternion: ArrayLike | None = None) -> SpinState:
    """
    Return the spin state through a sample: w [rad/yr] in body axes, principal ``inertia``.

    ``quaternion`` (body -> orbital, scalar first) gives the pole. Raises ValueError for a body
    at rest or bad inputs.
    """
    w = np.asarray(omega, dtype=float).reshape(3)
    moments = np.asarray(inertia, dtype=float).reshape(3)
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(moments)) and np.all(moments > 0)):
        raise ValueError(f'spin_state: omega and inertia must be finite (inertia > 0), got '
                         f'{w.tolist()}, {moments.tolist()}')
    order = np.argsort(moments, kind='stable')
    i1, i2, i3 = moments[order]
    w1, w2, w3 = w[order]
    energy = 0.5 * float(moments @ (w * w))
    momentum = float(np.linalg.norm(moments * w))
    if momentum == 0.0:
        raise ValueError('spin_state: the body is at rest (w = 0)')
    d = momentum * momentum / (2.0 * energy)
    pole: Vector3 | None = None
    lon = lat = None
    if quaternion is not None:
        c = quaternion_to_matrix(np.asarray(quaternion, dtype=float))
        direction = c @ (moments * w) / momentum
        pole = (float(direction[0]), float(direction[1]), float(direction[2]))
        lon = math.atan2(direction[1], direction[0])
        lat = math.asin(max(-1.0, min(1.0, direction[2])))
    principal = sum(abs(v) > 1e-12 * np.linalg.norm(w) for v in (w1, w2, w3)) == 1
    if principal or i1 == i3:   # (a sphere: every rotation is about a principal axis)
        period = 2.0 * math.pi / float(np.linalg.norm(w))
        return SpinState('principal', energy, momentum, d, period, period, pole, lon, lat)
    if abs(d - i2) <= _SEPARATRIX * i2 and i1 < i2 < i3:
        return SpinState('separatrix', energy, momentum, d, math.inf, math.inf, pole, lon, lat)
    l2, e2 = momentum * momentum, 2.0 * energy
    # m1 = 1 - k^2 as its own product: near the separatrix k^2 -> 1, and 1 - k^2 by
    # subtraction would lose the digits K(k) and the periods depend on
    if d > i2 or i2 == i1:            # SAM (I3 the reference axis); also I1 = I2 symmetric
        mode = 'SAM'
        scale = (i3 - i2) * (l2 - e2 * i1)
        m1 = (i3 - i1) * (l2 - e2 * i2) / scale if i2 > i1 else 1.0
    else:                              # LAM (I1 the reference axis); also I2 = I3 symmetric
        mode = 'LAM'
        scale = (i2 - i1) * (e2 * i3 - l2)
        m1 = (i3 - i1) * (e2 * i2 - l2) / scale if i3 > i2 else 1.0
    rotation = 4.0 * float(ellipkm1(m1)) * math.sqrt(i1 * i2 * i3 / scale)
    precession = _precession_period(mode, (i1, i2, i3), momentum, m1)
    return SpinState(mode, energy, momentum, d, rotation, precession, pole, lon, lat)


def _precession_period(mode: str, moments: tuple[float, float, float], momentum: float,
                       m1: float) -> float:
    """
    Return 2 pi / <phi'>: the mean precession of the reference axis about L [yr].

    ``mode`` 'SAM' or 'LAM', ``moments`` (I1, I2, I3) sorted, ``momentum`` |L|, ``m1`` = 1 - k^2
    of the polhode (the closed form of the module docstring).
    """
    i1, i2, i3 = moments
    if mode == 'SAM':
        n = -i3 * (i2 - i1) / (i1 * (i3 - i2)) if i2 > i1 else 0.0
    else:
        n = -i1 * (i3 - i2) / (i3 * (i2 - i1)) if i3 > i2 else 0.0
    pi_over_k = 1.0 + n / 3.0 * (float(elliprj(0.0, m1, 1.0, 1.0 - n))
                                 / float(elliprf(0.0, m1, 1.0)))
    spread = momentum * (1.0 / i1 - 1.0 / i3) * pi_over_k
    rate = momentum / i3 + spread if mode == 'SAM' else momentum / i1 - spread
    return 2.0 * math.pi / abs(rate)


def omega_for_periods(inertia: ArrayLike, precession_period: float,
                      rotation_period: float, mode: str = 'SAM') -> np.ndarray:
    """
    Return a w [rad/yr] (body axes) of the ``mode`` ('SAM' or 'LAM') with the given periods [yr].

    The inverse of :func:`spin_state`, how photometric solutions state a tumbler (e.g. Apophis:
    P_phi = 27.374 h, P_psi = 262.2 h, a SAM). At a fixed dynamical moment D = L^2/2E both
    periods scale as 1/L, so their ratio fixes D (a root in (I2, I3) for a SAM, in (I1, I2) for
    a LAM) and P_phi then fixes L. The w returned is the point of the polhode where the
    intermediate axis' component is 0, with the short and long axes' components > 0; the rest
    of the polhode is that state moved on by the torque-free motion. Raises ValueError when no
    such mode of these moments has these periods.
    """
    moments = np.asarray(inertia, dtype=float).reshape(3)
    order = np.argsort(moments, kind='stable')
    i1, i2, i3 = moments[order]
    if not (0.0 < i1 < i2 < i3 and precession_period > 0.0 and rotation_period > 0.0
            and mode in _MODE_NAMES):
        raise ValueError(f'omega_for_periods: needs I1 < I2 < I3 (a triaxial body), periods '
                         f'> 0 and a mode SAM or LAM, got {moments.tolist()}, '
                         f'{precession_period!r}, {rotation_period!r}, {mode!r}')

    def polhode_point(d: float, momentum: float) -> np.ndarray:
        e2 = momentum * momentum / d                               # 2E
        w1 = math.sqrt((momentum * momentum - e2 * i3) / (i1 * (i1 - i3)))
        w3 = math.sqrt((momentum * momentum - e2 * i1) / (i3 * (i3 - i1)))
        w = np.empty(3)
        w[order] = (w1, 0.0, w3)
        return w

    def periods(d: float) -> SpinState:
        return spin_state(polhode_point(d, 1.0), moments)

    target = rotation_period / precession_period

    def mismatch(d: float) -> float:
        state = periods(d)
        return state.rotation_period / state.precession_period - target

    # (D between the pure spin about the reference axis and the separatrix, both left out)
    low, high = (i2, i3) if mode == 'SAM' else (i1, i2)
    span = high - low
    low, high = low + 1e-9 * span, high - 1e-9 * span
    if mismatch(low) * mismatch(high) > 0.0:
        ends = sorted(periods(d).rotation_period / periods(d).precession_period
                      for d in (low, high))
        raise ValueError(f'omega_for_periods: no {_MODE_NAMES[mode]} of these moments has '
                         f'P_psi / P_phi = {target:.6g} (its ratios lie between '
                         f'{ends[0]:.6g} and {ends[1]:.6g})')
    # scipy.optimize here, not at import: it costs 0.2-0.4 s, and the analysis of every
    # recording imports this module (benchmarks/HISTORY.md, the Fig 9 main job)
    from scipy.optimize import brentq
    d = brentq(mismatch, low, high, xtol=1e-15 * i3, rtol=1e-14)
    unit = periods(d)
    return polhode_point(d, unit.precession_period / precession_period)
