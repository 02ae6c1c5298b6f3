"""
The comparator's error: how far the analytic model's w is from the simulated w.

Rates in rad/yr, body axes (the error vector is w_numeric - w_model, both in body axes); times
in simulated years. The norms come, in order of preference, from ``comparison/error_norm``,
``comparison/error`` or ``comparison/model_angular_velocity`` (docs/analysis.md).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tumble_ros.core import DEPARTURE
from tumble_ros.topics import ANGULAR_VELOCITY, ERROR, ERROR_NORM, MODEL_ANGULAR_VELOCITY

from .recording import Recording
from .timeaxis import same_stamps

__all__ = ['ErrorStats', 'comparator_errors']


@dataclass(frozen=True)
class ErrorStats:
    """
    Max and RMS of the comparator's error, absolute and relative.

    Absolute: |w_numeric - w_model| (rad/yr); relative: |error| / |w_numeric|.
    """

    models: tuple[str, ...]
    source: str              # the topic the norms come from
    n: int
    max_abs: float
    t_max_abs: float
    rms_abs: float
    max_rel: float | None
    t_max_rel: float | None
    rms_rel: float | None
    infinite_rel: int        # samples with |w_numeric| = 0 (relative error infinite), left out
    max_component: tuple[float, float, float] | None   # max |error_i|, if the vectors are known
    #: first t [yr] where relative > core.DEPARTURE (the model left the numeric solution), and
    #: how many samples are beyond it
    t_departure: float | None = None
    departed: int = 0


def comparator_errors(rec: Recording) -> tuple[ErrorStats | None, str | None]:
    """
    (stats, None) or (None, why there are none).

    Sources in order of preference: ``/comparison/error_norm`` (norm and relative as the
    comparator computed them), ``/comparison/error`` (norm of the vector; relative to
    |w_numeric| at the same stamp), ``/comparison/model_angular_velocity`` (error = w - model
    at the same stamps).
    """
    models: tuple[str, ...] = rec.error_models
    if not models and rec.comparator_status is not None:
        name = rec.comparator_status.values.get('model')
        models = (name,) if name else ()
    vectors = None
    if len(rec.error_norm):
        t, norm, rel = rec.norm_t, rec.error_norm, rec.error_relative
        source = rec.topic(ERROR_NORM)
        if len(rec.error_t):
            vectors = rec.error
    elif len(rec.error_t):
        t, vectors, source = rec.error_t, rec.error, rec.topic(ERROR)
        norm = np.linalg.norm(vectors, axis=1)
        rel = np.full(len(t), np.nan)
        ia, ib = same_stamps(t, rec.t)
        rel[ia] = norm[ia] / np.linalg.norm(rec.omega[ib], axis=1)
    elif len(rec.model_t):
        ia, ib = same_stamps(rec.model_t, rec.t)
        if len(ia) == 0:
            return None, (f'{rec.topic(MODEL_ANGULAR_VELOCITY)} has no sample at a stamp of '
                          f'{rec.topic(ANGULAR_VELOCITY)}')
        t = rec.t[ib]
        vectors = rec.omega[ib] - rec.model_omega[ia]
        source = f'{rec.topic(ANGULAR_VELOCITY)} - {rec.topic(MODEL_ANGULAR_VELOCITY)}'
        norm = np.linalg.norm(vectors, axis=1)
        with np.errstate(divide='ignore', invalid='ignore'):
            rel = norm / np.linalg.norm(rec.omega[ib], axis=1)
    else:
        reason = f'no comparator topics ({rec.topic("comparison/*")}) in the recording'
        if rec.comparator_status is not None:
            reason = (f'the comparator published no errors; its last status: '
                      f'{rec.comparator_status.level}: {rec.comparator_status.message}')
        return None, reason
    finite = np.isfinite(norm)
    if not finite.any():
        return None, f'{source}: no finite error value'
    k = int(np.nanargmax(np.where(finite, norm, np.nan)))
    rel_ok = np.isfinite(rel)
    infinite = int(np.sum(np.isinf(rel)))
    max_rel = t_max_rel = rms_rel = None
    if rel_ok.any():
        j = int(np.nanargmax(np.where(rel_ok, rel, np.nan)))
        max_rel, t_max_rel = float(rel[j]), float(t[j])
        rms_rel = float(np.sqrt(np.mean(rel[rel_ok] ** 2)))
    beyond = np.flatnonzero(rel_ok & (rel > DEPARTURE))
    t_departure = float(t[beyond[0]]) if len(beyond) else None
    comp = None
    if vectors is not None and len(vectors):
        cx, cy, cz = (float(v) for v in np.nanmax(np.abs(vectors), axis=0))
        comp = (cx, cy, cz)
    return ErrorStats(
        models=models, source=source, n=len(t), max_abs=float(norm[k]), t_max_abs=float(t[k]),
        rms_abs=float(np.sqrt(np.mean(norm[finite] ** 2))), max_rel=max_rel, t_max_rel=t_max_rel,
        rms_rel=rms_rel, infinite_rel=infinite, max_component=comp, t_departure=t_departure,
        departed=len(beyond)), None
