"""
Analytic models of the angular velocity, to compare with the numerical integration.

One interface, :class:`AnalyticModel`, a registry :data:`MODELS` and a factory
:func:`make_model`. Every model is built from an *anchor state*: the time ``t0`` [yr], the
angular velocity at ``t0`` [rad/yr, body axes] and the attitude at ``t0`` (the paper's Euler
angles or the body -> orbital quaternion). Its ``omega(t)`` meets that state exactly at
``t = t0``, so a comparator can re-anchor a model after an impact. Without an anchor the
scenario's initial state (``t0 = 0``, ``omega0``, ``euler0``) is used.

=========================  ==================================================================
name                       where it comes from
=========================  ==================================================================
``paper``                  paper eqs 16-19 with corrections 1-10 (symmetric body, Ix = Iy)
``fast_spin``              beyond the paper (correction 11): same linear equation, kinematics of
                           a fast spin about a fixed figure axis
``fast_spin_precessing``   beyond the paper (correction 11): ``fast_spin`` plus the
                           gravity-gradient precession Op of the figure axis, also added to
                           the frequency of the free (nutation) term
``fast_spin_adiabatic``    beyond the paper: ``fast_spin_precessing`` with the first-order
                           nutation-frequency shift (its theta dependence and its modulation
                           along the orbit) instead of Op
``torque_free_symmetric``  exact symmetric top, orbit_rate = 0
``torque_free_exact``      exact Euler-Poinsot motion (Jacobi elliptic functions), any body,
                           orbit_rate = 0
=========================  ==================================================================

The derivations, the differences from the print and the measured accuracy of each model
are in ``docs/analytic.md``; the paper, and the corrections 1-11 to its print named here, in
``docs/paper.md``.

The four linearised models share one closed form. With a = (Iz - Ix)/Ix, b = 3 a ws^2 and
w = wx + i wy, Euler's equations of the symmetric body under the gravity-gradient torque
are exactly ``dw/dt = i lam w + b F(t)`` with lam = a wz and wz constant. Each model
approximates the forcing F by a sum of exponentials sum_k C_k exp(i W_k tau), tau = t - t0,
by prescribing the Euler angles; variation of constants then gives::

    w(t) = exp(i lam tau) w(t0)
           + b sum_k C_k tau exp(i (lam + W_k) tau / 2) sinc((W_k - lam) tau / 2)

(sinc x = sin x / x), which is exact for that forcing, resonant (W_k = lam: secular growth
b C_k tau exp(i lam tau)) or not, and never divides by W_k - lam. ``fast_spin_adiabatic``
also modulates the phase of the first (free) term.

Frequencies: every model names the frequencies at which its wx and wy oscillate
(:meth:`AnalyticModel.frequencies`: |lam| and |W_k| for the linearised models, 2 pi/period
for the exact ones), and :func:`characteristic_frequencies` gathers those the theory expects
in a scenario's motion (the lines the offline analysis puts beside a recording's spectrum).

Units: time [yr], angles [rad], rates [rad/yr]. Plain numpy/scipy, no ROS.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
import math
from typing import Any, ClassVar, NamedTuple, Sequence

import numpy as np
import numpy.typing as npt

from tumble_ros.core.array_types import ArrayLike, FloatArray
from tumble_ros.core.model.rotation import quaternion_to_euler
from tumble_ros.core.model.scenario import ENCOUNTER_TORQUE_FRACTION, Scenario, ScenarioError

__all__ = [
    'AnalyticModel',
    'AnchorState',
    'ModelNotApplicable',
    'MODELS',
    'DEPARTURE',
    'departure_text',
    'make_model',
    'omega_many',
    'applicability',
    'PaperModel',
    'FastSpinModel',
    'FastSpinPrecessingModel',
    'FastSpinAdiabaticModel',
    'TorqueFreeSymmetricModel',
    'TorqueFreeExactModel',
    'SYMMETRY_TOL',
    'SEPARATRIX_TOL',
    'COS_THETA_TOL',
    'Frequency',
    'CharacteristicFrequencies',
    'characteristic_frequencies',
]

#: Two principal moments count as equal when they differ by at most this, relative.
SYMMETRY_TOL = 1e-12
#: A model has left the numeric solution once its relative error |w - w_model| / |w| exceeds
#: this: the error is then larger than the solution itself (the paper's model on Fig 9 grows
#: to +-4,400 rad/yr about a w of 30 rad/yr). The comparator says so on its status, the
#: analysis in its summary and figures (which scale w on the numeric solution).
DEPARTURE = 1.0
#: torque_free_exact refuses states with 1 - m below this (m the elliptic parameter):
#: scipy's ellipj switches to an O(1 - m) approximation above m = 1 - 1e-9.
SEPARATRIX_TOL = 1e-9
#: The paper's kinematics divide by cos(theta); refused below this.
COS_THETA_TOL = 1e-9
#: The meaning of wE = a w0, the free term of the symmetric body.
_FREE_NUTATION = 'free nutation wE = a w0'
#: (name, meaning) of a linearised model's free term, then of each forcing term (None: not listed).
_FrequencyNames = tuple[tuple[str, str], *tuple[tuple[str, str] | None, ...]]
#: A complex128 array (w = wx + i wy).
ComplexArray = npt.NDArray[np.complex128]


class ModelNotApplicable(ScenarioError):
    """
    An analytic model does not apply to a scenario or anchor state.

    The message starts with the offending field (as every ScenarioError) and names the
    model; ``model`` and ``reason`` hold the two parts.
    """

    def __init__(self, model: str, reason: str) -> None:
        super().__init__(f'{reason} (analytic model {model!r} does not apply; the '
                         "comparator's `model` parameter chooses another: docs/analytic.md "
                         'lists them and when each applies)')
        self.model = model
        self.reason = reason

    def __reduce__(self) -> tuple[type[ModelNotApplicable], tuple[str, str]]:
        return type(self), (self.model, self.reason)


@dataclass(frozen=True)
class Frequency:
    """
    A named angular frequency [rad/yr] at which wx and wy oscillate.

    ``omega`` is >= 0: w_perp = wx + i wy turning at W, either way, shows in wx at |W|.
    ``meaning`` says where the frequency comes from, in one line.
    """

    name: str
    omega: float
    meaning: str


@dataclass(frozen=True, slots=True)
class AnchorState:
    """
    The state a model starts from.

    Attributes
    ----------
    t0 : float
        Anchor time [yr].
    omega : (3,) array
        Angular velocity at t0 [rad/yr], body axes.
    euler : (3,) array
        The paper's Euler angles (phi, psi, theta) at t0 [rad].

    """

    t0: float
    omega: np.ndarray
    euler: np.ndarray

    @classmethod
    def build(cls, scenario: Scenario, t0: float = 0.0, omega: ArrayLike | None = None,
              quaternion: ArrayLike | None = None,
              euler: ArrayLike | None = None) -> 'AnchorState':
        """
        Anchor state from the optional pieces; defaults come from the scenario.

        ``omega`` defaults to ``scenario.omega0`` and the attitude to ``scenario.euler0``,
        but only for ``t0 = 0``: a later anchor needs both. Give the attitude either as
        ``euler`` (phi, psi, theta) or as ``quaternion`` (scalar first, body -> orbital).
        """
        t0 = float(t0)
        if not math.isfinite(t0):
            raise ScenarioError(f't0: must be finite, got {t0!r}')
        if t0 != 0.0 and (omega is None or (euler is None and quaternion is None)):
            raise ScenarioError(f't0: an anchor at t0 = {t0!r} != 0 needs omega and the attitude '
                                "(euler or quaternion) at t0; the scenario's initial state is at "
                                't = 0')
        if euler is not None and quaternion is not None:
            raise ScenarioError('quaternion: give the attitude as euler or as quaternion, '
                                'not both')
        # (the checks on Python floats: a comparator anchors once per impact)
        w = np.array(scenario.omega0 if omega is None else omega, dtype=float)
        if w.shape != (3,) or not all(map(math.isfinite, w.tolist())):
            raise ScenarioError(f'omega: must be 3 finite numbers, got {omega!r}')
        if quaternion is not None:
            q = np.asarray(quaternion, dtype=float)
            values = q.tolist() if q.shape == (4,) else [math.nan]
            # np.linalg.norm's arithmetic (the square root of q.dot(q)) without its checks, and
            # q / norm element by element on Python floats: the same bits
            norm = math.sqrt(q.dot(q)) if all(map(math.isfinite, values)) else math.nan
            if not norm > 0.0:
                raise ScenarioError(f'quaternion: must be 4 finite numbers, not all 0, '
                                    f'got {quaternion!r}')
            e = np.array(quaternion_to_euler([v / norm for v in values]))
        else:
            e = np.array(scenario.euler0 if euler is None else euler, dtype=float)
            if e.shape != (3,) or not np.all(np.isfinite(e)):
                raise ScenarioError(f'euler: must be 3 finite numbers (phi, psi, theta), '
                                    f'got {euler!r}')
        return cls(t0, w, e)


def _attitude_name(scenario: Scenario, state: AnchorState) -> str:
    if state.t0 == 0.0 and np.array_equal(state.euler, scenario.euler0):
        return 'euler0'
    return f'attitude at t0 = {state.t0:g}'


def _omega_name(scenario: Scenario, state: AnchorState) -> str:
    if state.t0 == 0.0 and np.array_equal(state.omega, scenario.omega0):
        return 'omega0'
    return f'omega at t0 = {state.t0:g}'


def _equal(x: float, y: float) -> bool:
    return abs(x - y) <= SYMMETRY_TOL * max(abs(x), abs(y))


class AnalyticModel(ABC):
    """
    An analytic angular velocity omega(t), anchored at a state.

    Subclasses set ``name`` (registry key) and ``label`` (where the model comes from) and
    implement ``_reason`` (why the model does not apply, or None) and ``_omega``.

    Parameters
    ----------
    scenario : Scenario
        Body, orbit and (when no anchor is given) initial state.
    t0, omega, quaternion, euler
        The anchor state (see :meth:`AnchorState.build`).

    Raises
    ------
    ModelNotApplicable
        (a ScenarioError, hence a ValueError) with the reason.

    """

    name: ClassVar[str]
    label: ClassVar[str]
    #: A model of the torque-free motion: it also applies outside a flyby's encounter window.
    torque_free: ClassVar[bool] = False

    def __init__(self, scenario: Scenario, t0: float = 0.0, omega: ArrayLike | None = None,
                 quaternion: ArrayLike | None = None, euler: ArrayLike | None = None) -> None:
        state = AnchorState.build(scenario, t0, omega, quaternion, euler)
        reason = type(self).applies(scenario, state)
        if reason is not None:
            raise ModelNotApplicable(self.name, reason)
        self.scenario = scenario
        self.state = state
        self._setup()

    @classmethod
    def applies(cls, scenario: Scenario, state: AnchorState | None = None) -> str | None:
        """
        None if the model applies to ``scenario`` (anchored at ``state``), else why not.

        ``state`` defaults to the scenario's initial state.
        """
        state = state if state is not None else AnchorState.build(scenario)
        if scenario.extra_torques:
            reason = _extra_torque_reason(scenario, state, cls.torque_free)
            if reason is not None:
                return reason
        return cls._reason(scenario, state)

    @classmethod
    @abstractmethod
    def _reason(cls, scenario: Scenario, state: AnchorState) -> str | None: ...

    def _setup(self) -> None:
        """Precompute constants from ``self.scenario`` and ``self.state``."""

    @property
    def t0(self) -> float:
        """Anchor time [yr]."""
        return self.state.t0

    def omega(self, t: ArrayLike) -> FloatArray:
        """Angular velocity [rad/yr], body axes, at times ``t`` [yr]: shape t.shape + (3,)."""
        t = np.asarray(t, dtype=float)
        return self._omega(t.reshape(-1) - self.state.t0).reshape(t.shape + (3,))

    @abstractmethod
    def _omega(self, tau: np.ndarray) -> np.ndarray:
        """(n, 3) angular velocity at tau = t - t0 (1-D)."""

    @abstractmethod
    def frequencies(self) -> tuple[Frequency, ...]:
        """
        Return the frequencies [rad/yr] at which this model's wx and wy oscillate, named.

        The free term's first, then the forced terms' (body axes, from the anchor state);
        empty for a constant omega.
        """

    def __repr__(self) -> str:
        return f'{type(self).__name__}(t0={self.state.t0!r}, omega={self.state.omega.tolist()!r})'


# --------------------------------------------------------------------------------------
# Linearised symmetric-body models (paper eqs 16-19 and beyond)
# --------------------------------------------------------------------------------------
def _forced_rotator(tau: FloatArray, lam: float | FloatArray, w_anchor: complex | ComplexArray,
                    b: float | FloatArray, coeffs: Sequence[complex] | ComplexArray,
                    freqs: Sequence[float] | FloatArray) -> ComplexArray:
    """
    Solution of dw/dt = i lam w + b sum_k C_k exp(i W_k tau), w(0) = w_anchor.

    Variation of constants; the sinc form covers resonant terms (W_k = lam) exactly and
    does not lose precision near them. The parameters are one model's numbers, or (n,) arrays
    of each sample's model (``coeffs`` and ``freqs``: (k, n)): the same operations element by
    element, hence the same bits (:func:`omega_many`).
    """
    w: ComplexArray = np.exp(1j * lam * tau) * w_anchor
    for c, om in zip(coeffs, freqs):
        half = 0.5 * (om - lam) * tau
        w = w + b * c * tau * np.exp(0.5j * (lam + om) * tau) * np.sinc(half / np.pi)
    return w


class _LinearSymmetric(AnalyticModel):
    """
    dw/dt = i lam w + b F(t) with F along prescribed kinematics (theta constant).

    Subclasses give the free frequency lam and the rates of psi and phi (``_rates``), and
    may modulate the phase of the free term (``_free_phase``; they then set ``joint`` False).
    """

    #: :meth:`omega_joint` evaluates the model (its free phase is not modulated).
    joint: ClassVar[bool] = True

    @classmethod
    def _reason(cls, scenario: Scenario, state: AnchorState) -> str | None:
        ix, iy, _ = scenario.inertia
        if not _equal(ix, iy):
            return (f'inertia: a linearised model needs a symmetric body, Ix == Iy within '
                    f'{SYMMETRY_TOL:g} relative; got {list(scenario.inertia)}')
        return None

    def _rates(self) -> tuple[float, float, float]:
        """(lam, psi_dot, phi_dot) [rad/yr]."""
        raise NotImplementedError

    def _free_phase(self, tau: np.ndarray) -> np.ndarray | None:
        """Extra phase [rad] of the free term exp(i lam tau) w(t0), zero at tau = 0; None: none."""
        return None

    def _frequency_names(self) -> _FrequencyNames:
        """(name, meaning) of the free term and of the forcing at ``freqs`` (None: not listed)."""
        raise NotImplementedError

    def frequencies(self) -> tuple[Frequency, ...]:
        """
        Return |lam| (the free term) and |W_k| (the forcing ``freqs``), named by the model.

        w = exp(i lam tau) w(t0) + b sum_k C_k (exp(i W_k tau) - exp(i lam tau))/(i (W_k - lam)):
        wx oscillates at these frequencies [rad/yr] and no other.
        """
        (free, meaning), *forced = self._frequency_names()
        out = [Frequency(free, abs(self.lam), meaning)]
        out += [Frequency(names[0], abs(w), names[1])
                for names, w in zip(forced, self.freqs) if names is not None]
        return tuple(out)

    def _setup(self) -> None:
        ix, _, iz = self.scenario.inertia
        ws = self.scenario.orbit_rate
        self.a = (iz - ix) / ix
        self.w0 = float(self.state.omega[2])
        self.b = 3.0 * self.a * ws * ws
        self.lam, self.psi_dot, self.phi_dot = self._rates()
        phi, psi, theta = (float(v) for v in self.state.euler)
        st, ct = math.sin(theta), math.cos(theta)
        self.beta0 = ws * self.state.t0 + phi  # beta = ws t + phi, at t0
        # F = (st/2) e^{-i psi} [-ct + (1 - ct)/2 e^{2 i beta} - (1 + ct)/2 e^{-2 i beta}]
        e_psi = np.exp(-1j * psi)
        e_2b = np.exp(2j * self.beta0)
        self.coeffs = (
            0.5 * st * e_psi * (-ct),
            0.5 * st * e_psi * 0.5 * (1.0 - ct) * e_2b,
            -0.5 * st * e_psi * 0.5 * (1.0 + ct) / e_2b,
        )
        self.beta_dot = ws + self.phi_dot
        self.freqs = (-self.psi_dot, -self.psi_dot + 2.0 * self.beta_dot,
                      -self.psi_dot - 2.0 * self.beta_dot)
        self.w_anchor = complex(self.state.omega[0], self.state.omega[1])

    @staticmethod
    def omega_joint(models: Sequence[_LinearSymmetric],
                    times: Sequence[FloatArray]) -> list[FloatArray]:
        """
        Return each model's omega at its times (1-D) [rad/yr], in one vectorised evaluation.

        Models whose :attr:`joint` holds: :meth:`omega`'s numbers bit for bit (each sample
        with its model's parameters, the same operations).
        """
        counts = [len(t) for t in times]
        if not counts:
            return []
        which = np.repeat(np.arange(len(models)), counts)
        t = np.concatenate([np.asarray(v, dtype=float).reshape(-1) for v in times])
        tau = t - np.array([m.state.t0 for m in models])[which]
        w = _forced_rotator(tau, np.array([m.lam for m in models])[which],
                            np.array([m.w_anchor for m in models])[which],
                            np.array([m.b for m in models])[which],
                            np.array([m.coeffs for m in models]).T[:, which],
                            np.array([m.freqs for m in models]).T[:, which])
        values = np.stack([w.real, w.imag, np.array([m.w0 for m in models])[which]], axis=-1)
        return np.split(values, np.cumsum(counts)[:-1])

    def _omega(self, tau: FloatArray) -> FloatArray:
        w = _forced_rotator(tau, self.lam, self.w_anchor, self.b, self.coeffs, self.freqs)
        extra = self._free_phase(tau)
        if extra is not None:
            w = w + np.expm1(1j * extra) * np.exp(1j * self.lam * tau) * self.w_anchor
        return np.stack([w.real, w.imag, np.full_like(tau, self.w0)], axis=-1)

    def euler(self, t: ArrayLike) -> FloatArray:
        """Return the model's kinematics (phi, psi, theta) [rad] at ``t``, shape t.shape + (3,)."""
        t = np.asarray(t, dtype=float)
        tau = t - self.state.t0
        phi, psi, theta = (float(v) for v in self.state.euler)
        return np.stack([phi + self.phi_dot * tau, psi + self.psi_dot * tau,
                         np.full_like(tau, theta)], -1)


class PaperModel(_LinearSymmetric):
    """
    The paper's approximate solution (eqs 16-19) with corrections 1-10 (docs/paper.md) applied.

    Regular precession of the figure axis about the orbit normal: theta constant,
    psi = psi0 - wE tau, phi = phi0 + (w0 + wE) tau / cos(theta), wE = a w0. The constant
    part of the forcing is then resonant with the free motion: a secular term of
    magnitude b sin(2 theta) / 4 per year (``secular_rate``).
    """

    name = 'paper'
    label = 'paper eqs 16-19 with corrections 1-10 (docs/paper.md)'

    @classmethod
    def _reason(cls, scenario: Scenario, state: AnchorState) -> str | None:
        reason = super()._reason(scenario, state)
        if reason is None and abs(math.cos(state.euler[2])) < COS_THETA_TOL:
            reason = (f'{_attitude_name(scenario, state)}: theta = {state.euler[2]!r} is pi/2 '
                      f"to within {COS_THETA_TOL:g}; the paper's phi rate (w0 + wE)/cos(theta) "
                      'diverges')
        return reason

    def _rates(self) -> tuple[float, float, float]:
        w_e = self.a * self.w0
        return w_e, -w_e, (self.w0 + w_e) / math.cos(self.state.euler[2])

    @property
    def w_a(self) -> float:
        """Return the paper's wA = 2 (ws + (w0 + wE)/cos theta) (correction 6) [rad/yr]."""
        return 2.0 * self.beta_dot

    def _frequency_names(self) -> _FrequencyNames:
        # forcing at wE (resonant with the free term: the same line), wE + wA and wE - wA
        forced = f"paper's forced term, wA = {self.w_a:.6g} rad/yr"
        return (('wE', _FREE_NUTATION), None, ('|wA+wE|', forced), ('|wA-wE|', forced))

    @property
    def secular_rate(self) -> float:
        """|d/dt| of the secular term, b |sin 2 theta| / 4 [rad/yr per yr]."""
        return abs(self.b * math.sin(2.0 * self.state.euler[2])) / 4.0


class FastSpinModel(_LinearSymmetric):
    """
    Fast spin about a figure axis fixed in space (correction 11, beyond the paper).

    theta and phi constant, psi = psi0 + w0 tau. Forcing frequencies -w0, -w0 +- 2 ws:
    no resonance with lam = a w0 (unless (1 + a) w0 = 0 or +-2 ws), no secular term.
    """

    name = 'fast_spin'
    label = ('beyond the paper (docs/paper.md, correction 11): linearised, fast spin about a '
             'fixed figure axis')

    def _rates(self) -> tuple[float, float, float]:
        return self.a * self.w0, self.w0, 0.0

    def _frequency_names(self) -> _FrequencyNames:
        # forcing at -w0, -w0 + 2 ws and -w0 - 2 ws
        return (('wE', _FREE_NUTATION), ('|w0|', 'fast-spin forced term (spin)'),
                ('|w0-2ws|', 'fast-spin forced term'), ('|w0+2ws|', 'fast-spin forced term'))


class _Precessing(_LinearSymmetric):
    """Fast spin with the figure axis precessing about the orbit normal at -Op."""

    @classmethod
    def _reason(cls, scenario: Scenario, state: AnchorState) -> str | None:
        reason = super()._reason(scenario, state)
        if reason is None and state.omega[2] == 0.0:
            reason = (f'{_omega_name(scenario, state)}: wz = 0; the precession rate '
                      '(3/2) ws^2 a cos(theta)/((1+a) wz) needs a spin about the figure axis')
        return reason

    @property
    def precession_rate(self) -> float:
        """Op = (3/2) ws^2 a cos(theta0)/((1 + a) w0) [rad/yr]; the axis turns at -Op about Z'."""
        return self.stiffness * math.cos(self.state.euler[2])

    @property
    def stiffness(self) -> float:
        """(3/2) ws^2 a / ((1 + a) w0) = Op / cos(theta0) [rad/yr]."""
        ws = self.scenario.orbit_rate
        return 1.5 * ws * ws * self.a / ((1.0 + self.a) * self.w0)

    def _precessing_rates(self, shift: float) -> tuple[float, float, float]:
        # phi turns at -Op (the measured drift of the numerics);
        # wz = psi' + phi' cos(theta) stays w0.
        op = self.precession_rate
        return self.a * self.w0 + shift, self.w0 + op * math.cos(self.state.euler[2]), -op

    def _forced_names(self) -> tuple[tuple[str, str], tuple[str, str], tuple[str, str]]:
        # forcing at -w0', -w0' + 2 ws' and -w0' - 2 ws' (w0' = psi', ws' = ws + phi')
        spin = f"forced term, w0' = w0 + Op cos(theta0) = {self.psi_dot:.6g} rad/yr"
        orbit = f"forced term, ws' = ws - Op = {self.beta_dot:.6g} rad/yr"
        return ("|w0'|", spin), ("|w0'-2ws'|", orbit), ("|w0'+2ws'|", orbit)


class FastSpinPrecessingModel(_Precessing):
    """
    ``fast_spin`` with the gravity-gradient precession (correction 11, beyond the paper).

    The figure axis precesses about the orbit normal at -Op, Op = (3/2) ws^2 a cos(theta0)
    / ((1 + a) w0): phi = phi0 - Op tau, psi = psi0 + (w0 + Op cos theta0) tau; and, as
    correction 11 prescribes, Op is added to the frequency of the free term: lam = a w0 + Op.
    The sign was measured (docs/analytic.md). Op is the small-theta limit of the shift;
    ``fast_spin_adiabatic`` has the theta dependence.
    """

    name = 'fast_spin_precessing'
    label = ('beyond the paper (docs/paper.md, correction 11): fast_spin with the '
             'gravity-gradient precession '
             'Op = (3/2) ws^2 a cos(theta0)/((1+a) w0) of the figure axis and of the free '
             "term's phase")

    def _rates(self) -> tuple[float, float, float]:
        return self._precessing_rates(self.precession_rate)

    def _frequency_names(self) -> _FrequencyNames:
        free = f'fast-spin nutation with the precession Op = {self.precession_rate:.4g}'
        return (('|wE+Op|', free),) + self._forced_names()


class FastSpinAdiabaticModel(_Precessing):
    """
    ``fast_spin_precessing`` with the nutation-frequency shift derived to first order.

    The tidal potential V = (3/2) ws^2 (Iz - Ix) (u.k)^2 (k the figure axis) shifts the
    body-frame frequency of the free term by (its Laplacian on the unit sphere) / (2 Iz w0),
    followed adiabatically along the orbit:
    delta(t) = S [(3 cos^2 theta - 1)/2 - (3/2) sin^2 theta cos 2 beta(t)],
    S = (3/2) ws^2 a / ((1 + a) w0). Its mean S (3 cos^2 theta - 1)/2 tends to Op as theta -> 0
    and vanishes at cos^2 theta = 1/3. Derivation in docs/analytic.md.
    """

    name = 'fast_spin_adiabatic'
    joint = False   # (its free phase is modulated along the orbit: one model at a time)
    label = ('beyond the paper: fast_spin_precessing with the first-order nutation-frequency '
             'shift S[(3cos^2 theta-1)/2 - (3/2) sin^2 theta cos 2 beta(t)], '
             'S = (3/2) ws^2 a/((1+a) w0)')

    @property
    def mean_shift(self) -> float:
        """Mean shift of the nutation frequency, dbar = S (3 cos^2 theta0 - 1)/2 [rad/yr]."""
        return self.stiffness * (3.0 * math.cos(self.state.euler[2]) ** 2 - 1.0) / 2.0

    def _rates(self) -> tuple[float, float, float]:
        return self._precessing_rates(self.mean_shift)

    def _frequency_names(self) -> _FrequencyNames:
        free = f'fast-spin nutation with the tidal shift dbar = {self.mean_shift:.4g}'
        return (('|wE+dbar|', free),) + self._forced_names()

    def _free_phase(self, tau: FloatArray) -> FloatArray:
        # integral over [t0, t] of -(3/2) S sin^2(theta) cos 2 beta, beta = beta0 + beta_dot tau,
        # written without dividing by beta_dot: (sin(2b0 + 2 bd tau) - sin 2b0)/(2 bd)
        #   = tau cos(2 b0 + bd tau) sinc(bd tau)
        s = math.sin(self.state.euler[2])
        bd = self.beta_dot
        integral = tau * np.cos(2.0 * self.beta0 + bd * tau) * np.sinc(bd * tau / np.pi)
        return -1.5 * self.stiffness * s * s * integral


# --------------------------------------------------------------------------------------
# Torque-free exact models
# --------------------------------------------------------------------------------------
def _extra_torque_reason(scenario: Scenario, state: AnchorState, torque_free: bool) -> str | None:
    """
    Return why a model does not apply to a scenario with torques beyond the circular orbit's.

    None for a torque-free model anchored outside a flyby's encounter window (the only extra
    torque being the flyby's): there the motion is torque-free to ENCOUNTER_TORQUE_FRACTION,
    and the simulator describes the state at the window's edges, where the comparator stops
    comparing and anchors again.
    """
    window = scenario.encounter_window
    names = ', '.join(t.name for t in scenario.extra_torques)
    several = len(scenario.all_perturbers) > 1   # (the window is the first one's)
    if not torque_free or window is None or scenario.torques or several:
        return ("the analytic models know the circular orbit's torque only; this scenario "
                f'also has {names}'
                + ('' if window is None or scenario.torques or several else
                   ' (outside its encounter window the torque-free models apply)'))
    t_in, t_out = window
    if t_in <= state.t0 < t_out:
        orbit = scenario.primary_orbit
        assert orbit is not None  # an encounter window is a flyby orbit's
        distance = orbit.pericentre * ENCOUNTER_TORQUE_FRACTION ** (-1.0 / 3.0)
        return (f"t0: inside the flyby's encounter window: from t = {t_in:.9g} to "
                f'{t_out:.9g} yr its tidal torque exceeds {ENCOUNTER_TORQUE_FRACTION:g} of the '
                f'perigee value (R < {distance:.6g} km) and no analytic model applies; the '
                'torque-free model anchors again at its end')
    return None


def _torque_free_reason(scenario: Scenario) -> str | None:
    if scenario.orbit_rate != 0.0:
        return (f'orbit_rate: the exact free-body solution needs no torque, orbit_rate = 0; '
                f'got {scenario.orbit_rate!r}')
    return None


class TorqueFreeSymmetricModel(AnalyticModel):
    """Exact symmetric top (Ix = Iy, orbit_rate = 0): w_perp turns at wE = a wz, wz constant."""

    name = 'torque_free_symmetric'
    torque_free = True
    label = "exact: torque-free symmetric top (Euler's equations, Ix = Iy)"

    @classmethod
    def _reason(cls, scenario: Scenario, state: AnchorState) -> str | None:
        reason = _torque_free_reason(scenario)
        ix, iy, _ = scenario.inertia
        if reason is None and not _equal(ix, iy):
            reason = (f'inertia: the symmetric top needs Ix == Iy within {SYMMETRY_TOL:g} '
                      f'relative; got {list(scenario.inertia)} (use torque_free_exact)')
        return reason

    def _setup(self) -> None:
        ix, _, iz = self.scenario.inertia
        self.w_e = (iz - ix) / ix * float(self.state.omega[2])

    def _omega(self, tau: FloatArray) -> FloatArray:
        w = np.exp(1j * self.w_e * tau) * complex(self.state.omega[0], self.state.omega[1])
        return np.stack([w.real, w.imag, np.full_like(tau, self.state.omega[2])], axis=-1)

    def frequencies(self) -> tuple[Frequency, ...]:
        """Return wE = |a wz|, the one frequency of wx [rad/yr]."""
        return (Frequency('wE', abs(self.w_e), _FREE_NUTATION),)


def _is_cyclic(i: int, j: int, k: int) -> bool:
    return (j - i) % 3 == 1 and (k - j) % 3 == 1


class TorqueFreeExactModel(AnalyticModel):
    """
    Exact Euler-Poinsot motion of any rigid body (orbit_rate = 0).

    The moments are sorted internally. With 2E = sum I w^2, L^2 = sum I^2 w^2 and I_mid
    the middle moment, the axis whose component never changes sign is p (the largest
    moment if L^2 > 2 E I_mid, short-axis mode; the smallest if L^2 < 2 E I_mid, long-axis
    mode), q is the middle axis and r the remaining one::

        w_r = A_r cn(u), w_q = A_q sn(u), w_p = A_p dn(u),   u = u0 + nu tau, parameter m.

    Two equal moments: the symmetric top about the third axis; three: constant omega.
    States within ``SEPARATRIX_TOL`` of the separatrix (1 - m) are refused.
    """

    name = 'torque_free_exact'
    torque_free = True
    label = 'exact: torque-free Euler-Poinsot solution (Jacobi elliptic functions)'

    @classmethod
    def _reason(cls, scenario: Scenario, state: AnchorState) -> str | None:
        reason = _torque_free_reason(scenario)
        if reason is None:
            setup = cls._solve(scenario.inertia, state.omega)
            if isinstance(setup, str):
                reason = f'{_omega_name(scenario, state)}: {setup}'
        return reason

    @staticmethod
    def _solve(inertia: Sequence[float] | FloatArray,
               w: Sequence[float] | FloatArray) -> tuple[str, tuple[Any, ...]] | str:
        """('const' | 'sym' | 'ell', parameters) for the state, or a reason string."""
        inertia = [float(v) for v in inertia]
        w = [float(v) for v in w]
        lo, q, hi = (int(k) for k in np.argsort(inertia, kind='stable'))
        i_lo, i_q, i_hi = inertia[lo], inertia[q], inertia[hi]
        eq_lo, eq_hi = _equal(i_lo, i_q), _equal(i_q, i_hi)
        if eq_lo and eq_hi:
            return 'const', ()
        if eq_lo or eq_hi:
            p = hi if eq_lo else lo  # the distinct moment: the symmetry axis
            j, k = (p + 1) % 3, (p + 2) % 3  # (p, j, k) cyclic
            i_perp = 0.5 * (inertia[j] + inertia[k])
            lam = (inertia[p] - i_perp) / i_perp * w[p]
            return 'sym', (p, j, k, lam)
        if w[lo] == 0.0 and w[hi] == 0.0:
            return 'const', ()  # steady spin about the middle axis (an unstable equilibrium)
        # L^2 - 2E I_q without cancellation between large terms of the same sign:
        d_mid = i_lo * (i_lo - i_q) * w[lo] ** 2 + i_hi * (i_hi - i_q) * w[hi] ** 2
        if d_mid > 0.0:
            p, r = hi, lo  # short-axis mode: w_hi never changes sign
        else:
            p, r = lo, hi  # long-axis mode: w_lo never changes sign
        i_p, i_r = inertia[p], inertia[r]
        # 2E I_p - L^2 = sum_i I_i (I_p - I_i) w_i^2 and L^2 - 2E I_r = sum_i I_i (I_i - I_r) w_i^2
        e_p = i_r * (i_p - i_r) * w[r] ** 2 + i_q * (i_p - i_q) * w[q] ** 2
        e_r = i_q * (i_q - i_r) * w[q] ** 2 + i_p * (i_p - i_r) * w[p] ** 2
        if e_p == 0.0:
            return 'const', ()  # steady spin about p
        a_r = math.sqrt(e_p / (i_r * (i_p - i_r)))
        a_q = math.sqrt(e_p / (i_q * (i_p - i_q)))
        a_p = math.copysign(math.sqrt(e_r / (i_p * (i_p - i_r))), w[p])
        den = (i_p - i_q) * e_r
        m = (i_q - i_r) * e_p / den
        m1 = (i_p - i_r) * d_mid / den  # 1 - m, without cancellation
        if not m1 >= SEPARATRIX_TOL:
            return (f'the state is within {SEPARATRIX_TOL:g} of the separatrix L^2 = 2 E I_mid '
                    f'(1 - m = {m1:.3g}): the elliptic solution is ill-conditioned there')
        sigma = 1.0 if _is_cyclic(r, q, p) else -1.0
        nu = sigma * math.copysign(1.0, w[p]) * math.copysign(1.0, i_p - i_q) * math.sqrt(
            (i_p - i_q) * e_r / (i_r * i_q * i_p))
        # scipy.special on first use, not with the module (~0.15-0.3 s: benchmarks/HISTORY.md,
        # "Node start-up")
        from scipy.special import ellipk, ellipkinc
        u0 = float(ellipkinc(math.atan2(w[q] / a_q, w[r] / a_r), m))
        period = 4.0 * float(ellipk(m))
        mode = 'short-axis' if p == hi else 'long-axis'
        return 'ell', (p, q, r, a_p, a_q, a_r, m, nu, u0, period, mode)

    def _setup(self) -> None:
        setup = self._solve(self.scenario.inertia, self.state.omega)
        assert not isinstance(setup, str)  # applies() refused the state otherwise
        self.kind, self.params = setup

    @property
    def mode(self) -> str:
        """'short-axis', 'long-axis', 'symmetric' or 'constant'."""
        return {'const': 'constant', 'sym': 'symmetric'}.get(self.kind) or self.params[-1]

    @property
    def period(self) -> float:
        """Period of omega in the body [yr] (inf for a constant omega)."""
        if self.kind == 'ell':
            return float(self.params[9] / abs(self.params[7]))
        if self.kind == 'sym' and self.params[3] != 0.0:
            return float(2.0 * math.pi / abs(self.params[3]))
        return math.inf

    def frequencies(self) -> tuple[Frequency, ...]:
        """Return 2 pi/period [rad/yr] (the fundamental of omega in the body); none if constant."""
        period = self.period
        if not (math.isfinite(period) and period > 0):
            return ()
        return (Frequency('Euler-Poinsot', 2 * math.pi / period,
                          f'torque-free period {period:.6g} yr ({self.mode})'),)

    def _omega(self, tau: FloatArray) -> FloatArray:
        w0 = self.state.omega
        out = np.empty(tau.shape + (3,))
        if self.kind == 'const':
            out[:] = w0
        elif self.kind == 'sym':
            p, j, k, lam = self.params
            w = np.exp(1j * lam * tau) * complex(w0[j], w0[k])
            out[:, p], out[:, j], out[:, k] = w0[p], w.real, w.imag
        else:
            p, q, r, a_p, a_q, a_r, m, nu, u0, period, _ = self.params
            u = np.mod(u0 + nu * tau, period)
            from scipy.special import ellipj
            sn, cn, dn, _ = ellipj(u, m)
            out[:, p], out[:, q], out[:, r] = a_p * dn, a_q * sn, a_r * cn
        return out


def omega_many(models: Sequence[AnalyticModel], times: Sequence[FloatArray]) -> list[FloatArray]:
    """
    Return ``[m.omega(t) for m, t in zip(models, times)]``, bit for bit, evaluated together.

    ``times``: 1-D arrays [yr]. The linearised models without a modulated free phase
    (``paper``, ``fast_spin``, ``fast_spin_precessing``) of one class are evaluated in one
    vectorised call, each sample with its own model's parameters (:func:`_forced_rotator`:
    the same operations element by element; tests/test_core_analytic.py compares the bits):
    a run with an impact every few samples anchors a model per impact, and one call per model
    costs ~40 us of numpy overhead. The others, one model at a time.
    """
    out: list[FloatArray | None] = [None] * len(models)
    groups: dict[type[AnalyticModel], list[int]] = {}
    for j, model in enumerate(models):
        if isinstance(model, _LinearSymmetric) and model.joint:
            groups.setdefault(type(model), []).append(j)
        else:
            out[j] = model.omega(times[j])
    for members in groups.values():
        group = [models[j] for j in members]
        assert all(isinstance(m, _LinearSymmetric) for m in group)
        values = _LinearSymmetric.omega_joint(group,  # type: ignore[arg-type]
                                              [times[j] for j in members])
        for j, v in zip(members, values):
            out[j] = v
    return out  # type: ignore[return-value]


# --------------------------------------------------------------------------------------
# Registry
# --------------------------------------------------------------------------------------
def departure_text(model_name: str, t: float) -> str:
    """Say that the model ``model_name`` left the numeric solution at ``t`` [yr]."""
    return (f'model {model_name!r} left the numeric solution at t = {t:.9g} yr '
            f'(|w - w_model| > {DEPARTURE:g} |w| from this sample on its segment); '
            'the comparisons go on')


MODELS: dict[str, type[AnalyticModel]] = {
    cls.name: cls
    for cls in (PaperModel, FastSpinModel, FastSpinPrecessingModel, FastSpinAdiabaticModel,
                TorqueFreeSymmetricModel, TorqueFreeExactModel)
}


def _model_class(name: str) -> type[AnalyticModel]:
    try:
        return MODELS[name]
    except (KeyError, TypeError):
        raise ScenarioError(f'model: unknown analytic model {name!r} '
                            f"(known: {', '.join(MODELS)})") from None


def make_model(name: str, scenario: Scenario, t0: float = 0.0, omega: ArrayLike | None = None,
               quaternion: ArrayLike | None = None,
               euler: ArrayLike | None = None) -> AnalyticModel:
    """
    Build the analytic model ``name`` anchored at (t0, omega, attitude).

    Without ``omega`` and an attitude the scenario's initial state is used (t0 must then
    be 0). Raises ScenarioError for an unknown name or a bad anchor, and its subclass
    ModelNotApplicable, with the reason, when the model does not apply.
    """
    return _model_class(name)(scenario, t0=t0, omega=omega, quaternion=quaternion, euler=euler)


def applicability(scenario: Scenario, state: AnchorState | None = None) -> dict[str, str | None]:
    """{model name: None if it applies, else the reason} for every registered model."""
    state = state if state is not None else AnchorState.build(scenario)
    return {name: cls.applies(scenario, state) for name, cls in MODELS.items()}


# --------------------------------------------------------------------------------------
# The frequencies the theory expects in a scenario's motion
# --------------------------------------------------------------------------------------
class CharacteristicFrequencies(NamedTuple):
    """The frequencies [rad/yr] expected in wx, and one line saying what they rest on."""

    lines: tuple[Frequency, ...]
    basis: str


def _named(model: AnalyticModel) -> dict[str, Frequency]:
    return {f.name: f for f in model.frequencies()}


def characteristic_frequencies(scenario: Scenario,
                               omega_max: float | None = None) -> CharacteristicFrequencies:
    """
    Return the frequencies [rad/yr] the theory expects in wx, asked of the models.

    From the scenario's initial state (a = (Iz - Ix)/Ix, w0 = omega0[2], ws = orbit_rate,
    theta0 = euler0[2]). Symmetric body (Ix = Iy): ``wE`` (the free term of ``fast_spin``, or of
    ``torque_free_symmetric`` without torque, then the only line); with torque also the paper's
    forced ``|wA-wE|``, ``|wA+wE|`` (if ``paper`` applies), the forced ``|w0|``, ``|w0-2ws|``,
    ``|w0+2ws|`` of ``fast_spin`` and the nutation with the tidal shift ``|wE+dbar|`` of
    ``fast_spin_adiabatic`` (if it applies). Asymmetric body: without torque the Euler-Poinsot
    frequency of ``torque_free_exact``; with torque no model applies, so two estimates: the
    Euler-equation rate max_i |Ij - Ik|/Ii * omega_max and the forcing omega_max + 2 ws, with
    ``omega_max`` the largest |w| of the motion (default |omega0|).
    """
    ix, iy, iz = scenario.inertia
    ws = scenario.orbit_rate
    w0 = scenario.omega0[2]
    theta = scenario.euler0[2]
    moments = (ix, iy, iz)
    if scenario.extra_torques:   # an orbit or torques the models do not know: estimates only
        w_max = float(np.linalg.norm(scenario.omega0)) if omega_max is None else float(omega_max)
        rate = max(abs(moments[(i + 1) % 3] - moments[(i + 2) % 3]) / moments[i]
                   for i in range(3))
        names = ', '.join(t.name for t in scenario.extra_torques)
        return CharacteristicFrequencies((
            Frequency('nutation (estimate)', rate * w_max,
                      'max |Ij - Ik|/Ii * max|w| (no model knows the torque)'),
        ), f'inertia {moments}, torques beyond the circular orbit ({names}): estimates only')
    if _equal(ix, iy):
        basis = (f'symmetric body: a = {(iz - ix) / ix:.6g}, w0 = {w0:.6g} rad/yr, '
                 f'ws = {ws:.6g} rad/yr, theta0 = {theta:.6g} rad (scenario inputs)')
        if ws == 0.0:
            return CharacteristicFrequencies(TorqueFreeSymmetricModel(scenario).frequencies(),
                                             basis + '; no torque: wE only (exact)')
        fast = _named(FastSpinModel(scenario))
        lines = [fast['wE']]
        if PaperModel.applies(scenario) is None:
            paper = _named(PaperModel(scenario))
            lines += [paper['|wA-wE|'], paper['|wA+wE|']]
        lines += [fast['|w0|'], fast['|w0-2ws|'], fast['|w0+2ws|']]
        if FastSpinAdiabaticModel.applies(scenario) is None:
            lines.append(_named(FastSpinAdiabaticModel(scenario))['|wE+dbar|'])
        return CharacteristicFrequencies(tuple(lines), basis)
    basis = f'asymmetric body: inertia {moments}, ws = {ws:.6g} rad/yr'
    if ws == 0.0:
        try:
            model = TorqueFreeExactModel(scenario)
        except ModelNotApplicable as err:
            return CharacteristicFrequencies((), basis + f'; no torque-free frequency: {err}')
        return CharacteristicFrequencies(model.frequencies(),
                                         basis + '; no torque: Euler-Poinsot motion (exact)')
    w_max = float(np.linalg.norm(scenario.omega0)) if omega_max is None else float(omega_max)
    rate = max(abs(moments[(i + 1) % 3] - moments[(i + 2) % 3]) / moments[i] for i in range(3))
    return CharacteristicFrequencies((
        Frequency('nutation (estimate)', rate * w_max,
                  'max |Ij - Ik|/Ii * max|w| (no linear theory for Ix != Iy)'),
        Frequency('|w|+2ws (estimate)', w_max + 2 * ws, 'forcing, upper estimate'),
    ), basis + '; estimates only')
