"""
The spin state as the literature gives it: periods, mode, L's direction, inertia ratios, phases.

A tumbler's photometric solution (Kaasalainen 2001, A&A 376, 302; Pravec et al. 2005, Icarus 173,
108; 2014, Icarus 233, 48) states its torque-free spin state by

* the **mode**, SAM (short-axis) or LAM (long-axis), and the **reference axis** r of its Euler
  angles: I3 (the largest moment) in a SAM, I1 (the smallest) in a LAM;
* the **periods** P_phi (the mean precession of r about L) and P_psi (the rotation about r, the
  period of w in body axes), as :func:`~.spinstate.spin_state` defines them;
* the **inertia ratios** I1/I3 and I2/I3 (I1 < I2 < I3; Kaasalainen 2001's convention);
* **L's direction**, longitude lambda (from +X' towards +Y') and latitude beta (from the X'Y'
  plane) in the scenario's orbital frame X'Y'Z': ecliptic longitude and latitude when the
  scenario's orbital frame is ecliptic J2000 (as ``config/apophis_2029.yaml``'s), and only then;
* the **phases at the epoch** (t = 0): the Euler angles (phi0, psi0) of the body in the frame
  of L, z-x-z as the paper's (``rotation.euler_to_matrix``): ``R(phi, psi, theta) =
  Rz(psi) Rx(theta) Rz(phi)`` maps L-frame components to the body's (a, b, r) components, with
  (a, b, r) = (I1, I2, I3) in a SAM and (I2, I3, I1) in a LAM. The L frame has z_L along L and
  x_L = (-sin lambda, cos lambda, 0), the ascending node of L's equator on the X'Y' plane
  (defined at the poles too); y_L = z_L x x_L. theta0 is not free: the energy fixes
  cos^2 theta = (1/D - S) / (1/I_r - S), S = sin^2 psi / I_a + cos^2 psi / I_b, D = L^2/2E;
  ``anti_aligned`` picks its sign (false: theta0 <= 90 deg, r in L's hemisphere; true: the body
  turns the other way about r).

:class:`SpinObservables` holds such a state, validated once (a ScenarioError names the
``spin.*`` field); :meth:`SpinObservables.scenario_fields` converts it to the scenario's inertia,
omega0 and euler0 (the params file's ``spin.*`` block: ``Scenario.from_parameters``), and
:func:`observe` is the reverse: the literature's state of any (w, attitude). The principal axes
are e1, e3 along the body's smallest and largest moments' +axes and e2 = e3 x e1 (an inertia
listed in another order than (I1, I2, I3) keeps right-handed axes).

Units: periods [yr] (the params file: its ``time_unit``), angles [rad], w [rad/yr].
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from types import ModuleType
from typing import Any, Mapping

import numpy as np

from tumble_ros.core.array_types import ArrayLike
from tumble_ros.core.model.limits import ScenarioError
from tumble_ros.core.model.rotation import euler_to_matrix, matrix_to_euler, quaternion_to_matrix

__all__ = ['SpinObservables', 'observe', 'SPIN_MODES', 'SPIN_PARAMETER_DOCS',
           'SPIN_DEFAULTS', 'spin_from_parameters']

#: The modes a literature state may have.
SPIN_MODES = ('SAM', 'LAM')
#: Largest relative difference between the inertia ratios and the scenario's moments.
RATIO_TOLERANCE = 1e-9
_TWO_PI = 2.0 * math.pi


def _spinstate() -> ModuleType:
    """
    Return :mod:`~.spinstate`, imported on first use.

    It imports scipy.special, which no node module may import at start-up (the scenario imports
    this module; test_node_startup.py): only a scenario with a ``spin.*`` block needs it.
    """
    from tumble_ros.core.model import spinstate
    return spinstate


def _fail(name: str, why: str, value: Any) -> None:
    raise ScenarioError(f'spin.{name}: {why}, got {value!r}')


def _numbers(name: str, value: Any, n: int) -> tuple[float, ...]:
    """Return ``value`` as n finite floats, or fail naming ``spin.<name>``."""
    if isinstance(value, (str, bytes)) or not hasattr(value, '__len__') or len(value) != n:
        _fail(name, f'must be a list of {n} numbers', value)
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) \
                or not math.isfinite(float(v)):
            _fail(name, f'must be a list of {n} finite numbers', value)
        out.append(float(v))
    return tuple(out)


def _period(name: str, value: Any) -> float:
    """Return the period ``value`` as a float > 0, or fail naming ``spin.<name>``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
            or not (math.isfinite(float(value)) and float(value) > 0.0):
        _fail(name, 'must be a finite number > 0 (a period)', value)
    return float(value)


@dataclass(frozen=True)
class SpinObservables:
    """
    A torque-free spin state as photometry states it (module docstring: conventions, frames).

    Attributes
    ----------
    mode : 'SAM' or 'LAM'.
    precession_period : P_phi [yr].
    rotation_period : P_psi [yr].
    inertia_ratios : (I1/I3, I2/I3), 0 < I1/I3 < I2/I3 < 1.
    pole : (lambda, beta) [rad]: L's direction, orbital frame; beta in [-pi/2, pi/2], lambda
        kept in [0, 2 pi).
    phases : (phi0, psi0) [rad]: the Euler angles about L at the epoch, kept in [0, 2 pi).
    anti_aligned : theta0 > 90 deg (the reference axis away from L).

    """

    mode: str
    precession_period: float
    rotation_period: float
    inertia_ratios: tuple[float, float]
    pole: tuple[float, float]
    phases: tuple[float, float] = (0.0, 0.0)
    anti_aligned: bool = False

    def __post_init__(self) -> None:
        if self.mode not in SPIN_MODES:
            _fail('mode', f"must be one of {', '.join(SPIN_MODES)} (or '' for no spin block)",
                  self.mode)
        object.__setattr__(self, 'precession_period',
                           _period('precession_period', self.precession_period))
        object.__setattr__(self, 'rotation_period',
                           _period('rotation_period', self.rotation_period))
        r1, r2 = _numbers('inertia_ratios', self.inertia_ratios, 2)
        if not 0.0 < r1 < r2 < 1.0:
            _fail('inertia_ratios', 'must be (I1/I3, I2/I3) with 0 < I1/I3 < I2/I3 < 1 (a '
                  'triaxial body, I3 the largest moment)', self.inertia_ratios)
        object.__setattr__(self, 'inertia_ratios', (r1, r2))
        lon, lat = _numbers('pole', self.pole, 2)
        if not -math.pi / 2 <= lat <= math.pi / 2:
            _fail('pole', 'the latitude beta (second entry) must be in [-pi/2, pi/2] rad',
                  self.pole)
        object.__setattr__(self, 'pole', (lon % _TWO_PI, lat))
        phi, psi = _numbers('phases', self.phases, 2)
        object.__setattr__(self, 'phases', (phi % _TWO_PI, psi % _TWO_PI))
        if not isinstance(self.anti_aligned, (bool, np.bool_)):
            _fail('anti_aligned', 'must be true or false', self.anti_aligned)
        object.__setattr__(self, 'anti_aligned', bool(self.anti_aligned))
        self._check_periods((r1, r2, 1.0))

    def _check_periods(self, moments: tuple[float, float, float]) -> None:
        """Refuse a P_psi that no body of these ratios has in this mode with this P_phi."""
        omega_for_periods = _spinstate().omega_for_periods
        try:
            omega_for_periods(moments, self.precession_period, self.rotation_period, self.mode)
        except ValueError as err:
            why = str(err).split(': ', 1)[1]
            raise ScenarioError(f'spin.rotation_period: impossible with spin.precession_period = '
                                f'{self.precession_period!r} and spin.inertia_ratios = '
                                f'{list(self.inertia_ratios)}: {why}, got '
                                f'{self.rotation_period!r}') from None

    # -- the scenario's state ---------------------------------------------------------------
    def scenario_fields(self, inertia: ArrayLike | None = None) -> dict[str, Any]:
        """
        Return ``{'inertia', 'omega0', 'euler0'}`` of this state, for :class:`Scenario`.

        ``inertia``: the scenario's moments (any order, normalised or not) when it has its own
        (a stated ``inertia``, a mass model): their ratios must be these to
        :data:`RATIO_TOLERANCE`; None: (I1/I3, I2/I3, 1). omega0 [rad/yr] in body axes, euler0
        the paper's Euler angles (orbital -> body) [rad].
        """
        moments = self._moments(inertia)
        omega_for_periods = _spinstate().omega_for_periods
        axes = _principal_axes(moments)
        sam = self.mode == 'SAM'
        # (a, b, r) in body components: a SAM's (e1, e2, e3), a LAM's (e2, e3, e1)
        frame = axes if sam else axes[:, [1, 2, 0]]
        ia, ib, ir = (frame.T @ (moments[:, None] * frame)).diagonal()
        w_ref = omega_for_periods(moments, self.precession_period, self.rotation_period,
                                  self.mode)
        momentum = float(np.linalg.norm(moments * w_ref))
        dynamic = momentum * momentum / float(moments @ (w_ref * w_ref))
        phi, psi = self.phases
        s = math.sin(psi) ** 2 / ia + math.cos(psi) ** 2 / ib
        cos_theta = math.sqrt(min(1.0, max(0.0, (1.0 / dynamic - s) / (1.0 / ir - s))))
        theta = math.acos(-cos_theta if self.anti_aligned else cos_theta)
        to_abr = euler_to_matrix(phi, psi, theta)          # L frame -> (a, b, r)
        momentum_abr = momentum * to_abr[:, 2]
        omega = frame @ (momentum_abr / np.array([ia, ib, ir]))
        body_to_orbital = _l_frame(self.pole) @ to_abr.T @ frame.T
        return {'inertia': tuple(float(v) for v in moments),
                'omega0': tuple(float(v) for v in omega),
                'euler0': matrix_to_euler(body_to_orbital.T)}

    def _moments(self, inertia: ArrayLike | None) -> np.ndarray:
        """Return the scenario's moments: ``inertia`` checked against the ratios, or theirs."""
        r1, r2 = self.inertia_ratios
        if inertia is None:
            return np.array([r1, r2, 1.0])
        moments = np.asarray(inertia, dtype=float).reshape(3)
        ratios = np.sort(moments)[:2] / moments.max()
        if not np.all(np.abs(ratios - (r1, r2)) <= RATIO_TOLERANCE * np.array([r1, r2])):
            _fail('inertia_ratios', f"disagree with the scenario's moments {moments.tolist()} "
                  f'(their ratios are {ratios.tolist()}): give one or the other',
                  list(self.inertia_ratios))
        return moments

    # -- the params file's spin.* block -----------------------------------------------------
    def to_parameters(self) -> dict[str, Any]:
        """Return the ``spin.*`` parameters of this state (periods in years)."""
        return {'spin.mode': self.mode, 'spin.precession_period': self.precession_period,
                'spin.rotation_period': self.rotation_period,
                'spin.inertia_ratios': list(self.inertia_ratios), 'spin.pole': list(self.pole),
                'spin.phases': list(self.phases), 'spin.anti_aligned': self.anti_aligned}


def _principal_axes(moments: np.ndarray) -> np.ndarray:
    """Return (e1, e2, e3) as columns, body components: e1, e3 the +axes of I1, I3."""
    order = np.argsort(moments, kind='stable')
    eye = np.eye(3)
    e1, e3 = eye[order[0]], eye[order[2]]
    return np.column_stack([e1, np.cross(e3, e1), e3])


def _l_frame(pole: tuple[float, float]) -> np.ndarray:
    """Return the L frame's axes (x_L, y_L, z_L) as columns, orbital components."""
    lon, lat = pole
    z = np.array([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)])
    x = np.array([-math.sin(lon), math.cos(lon), 0.0])
    return np.column_stack([x, np.cross(z, x), z])


def observe(omega: ArrayLike, inertia: ArrayLike, quaternion: ArrayLike) -> SpinObservables:
    """
    Return the literature's spin state of w [rad/yr] (body axes) and the attitude ``quaternion``.

    The reverse of :meth:`SpinObservables.scenario_fields`: mode, periods and pole as
    :func:`~.spinstate.spin_state` reports them (what ``analyze`` reports), the ratios of
    ``inertia``, the phases from the attitude. Raises ScenarioError (``spin.mode``) for a state
    that is neither a SAM nor a LAM (a principal rotation, the separatrix) or a body that is not
    triaxial.
    """
    moments = np.asarray(inertia, dtype=float).reshape(3)
    state = _spinstate().spin_state(omega, moments, quaternion)
    if state.mode not in SPIN_MODES or len(set(moments.tolist())) < 3:
        _fail('mode', 'the state has no SAM/LAM description (a principal rotation, the '
              'separatrix or a body that is not triaxial)', state.mode)
    assert state.pole_longitude is not None and state.pole_latitude is not None
    pole = (state.pole_longitude, state.pole_latitude)
    axes = _principal_axes(moments)
    frame = axes if state.mode == 'SAM' else axes[:, [1, 2, 0]]
    to_abr = frame.T @ quaternion_to_matrix(np.asarray(quaternion, dtype=float)).T @ _l_frame(pole)
    phi, psi, theta = matrix_to_euler(to_abr)
    top = float(moments.max())
    ratios = np.sort(moments)[:2] / top
    return SpinObservables(state.mode, state.precession_period, state.rotation_period,
                           (float(ratios[0]), float(ratios[1])), pole, (phi, psi),
                           theta > math.pi / 2)


#: The ``spin.*`` parameters when no spin block is given (``spin.mode`` '').
SPIN_DEFAULTS: dict[str, Any] = {
    'spin.mode': '', 'spin.precession_period': 0.0, 'spin.rotation_period': 0.0,
    'spin.inertia_ratios': [0.0, 0.0], 'spin.pole': [0.0, 0.0], 'spin.phases': [0.0, 0.0],
    'spin.anti_aligned': False}

#: Unit and meaning of every ``spin.*`` parameter (the nodes' descriptors, docs/ros.md).
SPIN_PARAMETER_DOCS: dict[str, tuple[str, str]] = {
    'spin.mode': ('', 'the spin state as the literature gives it: SAM or LAM, with the spin.* '
                  "below instead of omega0, euler0 (and inertia); '' (default) = not used "
                  '(docs/physics.md, "The spin state from what is observed")'),
    'spin.precession_period': ('yr', 'P_phi, the mean precession period of the reference axis '
                               '(I3 in a SAM, I1 in a LAM) about L'),
    'spin.rotation_period': ('yr', 'P_psi, the rotation period about the reference axis (the '
                             'period of omega in body axes)'),
    'spin.inertia_ratios': ('', '(I1/I3, I2/I3), 0 < I1/I3 < I2/I3 < 1; inertia becomes (I1/I3, '
                            'I2/I3, 1) unless the scenario states its moments'),
    'spin.pole': ('rad', "L's direction (lambda, beta), orbital frame (ecliptic when the orbital "
                  'frame is ecliptic J2000)'),
    'spin.phases': ('rad', 'the Euler angles (phi0, psi0) of the body about L at t = 0'),
    'spin.anti_aligned': ('', 'theta0 > 90 deg: the reference axis points away from L'),
}


def spin_from_parameters(params: Mapping[str, Any]) -> SpinObservables | None:
    """
    Return the state of the ``spin.*`` keys of a flat mapping (periods in years), or None.

    None when ``spin.mode`` is '' (or absent); then every other ``spin.*`` must be at its
    default (a ScenarioError names the first that is not).
    """
    values = {k: params.get(k, d) for k, d in SPIN_DEFAULTS.items()}
    mode = values['spin.mode']
    if mode == '':
        for key, default in SPIN_DEFAULTS.items():
            if values[key] != default and not (isinstance(default, list)
                                               and list(values[key]) == default):
                _fail(key.split('.', 1)[1], 'is used only with spin.mode SAM or LAM (spin.mode '
                      "is '')", values[key])
        return None
    return SpinObservables(
        mode, values['spin.precession_period'], values['spin.rotation_period'],
        _list(values['spin.inertia_ratios']), _list(values['spin.pole']),
        _list(values['spin.phases']), values['spin.anti_aligned'])


def _list(value: Any) -> Any:
    """Return a list or tuple as a tuple (what the dataclass holds); anything else as it is."""
    return tuple(value) if isinstance(value, (list, tuple)) else value
