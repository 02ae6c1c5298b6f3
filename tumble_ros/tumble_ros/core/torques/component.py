"""
Torques from outside core: a compiled function and its parameters, added to the built-in ones.

The built-in torques (the circular-orbit gravity gradient, :mod:`.gravity_gradient`, and the
impact pulses, :mod:`.pulses`) are inlined into the kernels. Any other torque is a
:class:`TorqueComponent`: a function of the signature below, made with
:func:`torque_function`, and its parameters. Every integrator runs it unchanged: the compiled
loops call it through a function pointer (numba's first-class functions), the reference
steppers call the same function from Python. Nothing in the integrators changes for a new
torque::

    from tumble_ros.core.torques import TorqueComponent, torque_function

    @torque_function
    def spin_down(par, t, q0, q1, q2, q3):
        # a body-fixed torque about z [inertia units * rad/yr^2]
        return 0.0, 0.0, -par[0]

    scenario = Scenario(..., torques=(TorqueComponent('spin_down', spin_down, (0.5,)),))

The function gets ``par`` (float64 array: the component's ``parameters``), the absolute time
``t`` [yr] and the attitude quaternion ``q0..q3`` (body -> orbital, scalar first, of unit norm
to rounding), and returns the torque in body principal axes [inertia units * rad/yr^2]. It
must be written in the subset numba compiles (floats, ``math``, indexing ``par``). It may not
depend on the angular velocity: the splitting methods' kick holds the attitude fixed and must
be an exact flow.
"""
from __future__ import annotations

from dataclasses import dataclass
import functools
import math
from typing import Any, Callable, Iterable, Sequence
import warnings

import numpy as np
import numpy.typing as npt

from tumble_ros.core.compiling.jit import COMPILED

__all__ = ['TorqueComponent', 'torque_function', 'extra_torque_arrays', 'NO_EXTRA',
           'EXTRA_SLOTS']

if COMPILED:
    import numba
    from numba import types as _t
    from numba.core.ccallback import CFunc as _CFunc

    #: The signature of a torque function: (par, t, q0, q1, q2, q3) -> (Mx, My, Mz).
    SIGNATURE = _t.UniTuple(  # type: ignore[no-untyped-call]  # unannotated in numba
        _t.float64, 3)(_t.float64[::1], *([_t.float64] * 5))
    # numba calls first-class function types "experimental"; they are what lets a torque from
    # outside core reach the cached kernels without recompiling them
    warnings.filterwarnings('ignore', category=numba.NumbaExperimentalFeatureWarning)


def torque_function(f: Callable[..., Any]) -> Callable[..., Any]:
    """
    Make ``f(par, t, q0, q1, q2, q3) -> (Mx, My, Mz)`` a torque function the kernels can call.

    Compiled: a numba C callback of :data:`SIGNATURE` (cached when ``f`` lives in a file);
    without numba: ``f`` itself. Either is callable from Python.
    """
    if not COMPILED:
        return f
    try:
        return numba.cfunc(SIGNATURE, cache=True, error_model='numpy')(f)
    except RuntimeError:  # no file to cache into (defined interactively)
        return numba.cfunc(SIGNATURE, error_model='numpy')(f)


def _is_torque_function(f: Any) -> bool:
    if COMPILED:
        # (CFunc's signature attribute is not in numba's stubs)
        return isinstance(f, _CFunc) and f._sig == SIGNATURE  # type: ignore[attr-defined]
    return callable(f)


@dataclass(frozen=True)
class TorqueComponent:
    """
    An extra torque on the body: a named :func:`torque_function` and its parameters.

    Attributes
    ----------
    name : str
        What the torque is (shown in errors and descriptions).
    function : callable
        Made with :func:`torque_function`; body-axis torque [inertia units * rad/yr^2].
    parameters : tuple of float
        Handed to ``function`` as its float64 array ``par`` (units: the component's own).

    """

    name: str
    function: Callable[..., Any]
    parameters: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f'torques: name must be a non-empty string, got {self.name!r}')
        if not _is_torque_function(self.function):
            raise ValueError(f'torques[{self.name}].function: must be made with '
                             'tumble_ros.core.torques.torque_function (a compiled torque of '
                             f'signature (par, t, q0, q1, q2, q3) -> (Mx, My, Mz)), got '
                             f'{self.function!r}')
        try:
            params = tuple(float(v) for v in self.parameters)
        except (TypeError, ValueError):
            raise ValueError(f'torques[{self.name}].parameters: must be numbers, got '
                             f'{self.parameters!r}') from None
        if not all(math.isfinite(v) for v in params):
            raise ValueError(f'torques[{self.name}].parameters: must be finite, got {params}')
        object.__setattr__(self, 'parameters', params)
        value = self.torque(0.0, (1.0, 0.0, 0.0, 0.0))
        if value.shape != (3,):
            raise ValueError(f'torques[{self.name}].function: must return 3 numbers (Mx, My, Mz)')

    def torque(self, t: float, quaternion: Sequence[float] | npt.NDArray[np.float64],
               ) -> npt.NDArray[np.float64]:
        """Return the body-axis torque at time ``t`` [yr] and attitude ``quaternion``."""
        q = [float(v) for v in quaternion]
        par = np.array(self.parameters if self.parameters else (0.0,), dtype=np.float64)
        try:
            return np.array(self.function(par, float(t), *q), dtype=float).reshape(-1)
        except Exception as err:  # a user's function: say whose it was
            raise ValueError(f'torques[{self.name}].function failed: {err}') from err


#: The kernels' ``extra`` argument when there is no extra torque: None, for which numba
#: compiles the kernels without the calls (a separate specialisation, ~10 % faster).
NO_EXTRA = None


def extra_torque_arrays(components: Iterable[TorqueComponent],
                        ) -> tuple[tuple[Callable[..., Any], ...], npt.NDArray[np.float64]] | None:
    """
    Return the kernels' ``extra`` argument: (functions, parameters) of the components.

    ``parameters`` is (n, width) float64, row j the parameters of function j (zero-padded).
    ``functions`` holds the n components' functions, then a torque that is never called, up to
    a multiple of :data:`EXTRA_SLOTS`: the kernels call functions 0 ... n - 1 (the rows of
    ``parameters``), and their compiled variant depends on the tuple's length only.
    """
    listed = tuple(components)
    if not listed:
        return NO_EXTRA
    width = max(1, max(len(c.parameters) for c in listed))
    par = np.zeros((len(listed), width))
    for j, c in enumerate(listed):
        par[j, :len(c.parameters)] = c.parameters
    padding = (_unused(),) * (-len(listed) % EXTRA_SLOTS)
    return tuple(c.function for c in listed) + padding, par


#: The functions of ``extra`` come in tuples of a multiple of this length. numba types a tuple
#: by its length, and compiles each loop anew for each type (~10-20 s of CPU a method): with
#: the tuple padded, every scenario with 1 to 8 extra torques (perturbers, a field's degrees,
#: the user's own) runs the one variant ``make warmup`` compiles. Before, a flyby with the Moon
#: and the Sun, or a table and a Kepler orbit, compiled its own variant on its first run.
EXTRA_SLOTS = 8


def _never_called(par: Any, t: float, q0: float, q1: float, q2: float,
                  q3: float) -> tuple[float, float, float]:
    """Return no torque: the padding of ``extra``'s functions, never called (no row for it)."""
    return 0.0, 0.0, 0.0


@functools.cache
def _unused() -> Callable[..., Any]:
    """Return :func:`_never_called` compiled (on first use; cached: a module-level function)."""
    return torque_function(_never_called)
