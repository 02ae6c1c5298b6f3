"""
The ``body.*`` parameters of a scenario: which mass model gives the body's inertia.

``body.model`` is one of :data:`BODY_MODELS`:

- ``inertia`` (the default): the scenario's normalised ``inertia`` is the body, as in the
  paper; every other ``body.*`` parameter keeps its default;
- ``ellipsoid``: ``body.semi_axes`` [km], ``body.density`` [kg/m^3];
- ``polyhedron``: ``body.shape_file`` (a Wavefront OBJ or vertex/facet counts file, km;
  resolved by :func:`~tumble_ros.core.model.shape_files.resolve_shape_path`),
  ``body.density`` [kg/m^3]; the shape is moved into its centre-of-mass principal axes (the
  move: ``mass_model.reference``);
- ``moments``: ``body.mass`` [kg], ``body.reference_radius`` [km], ``body.principal_moments``
  [kg km^2] and ``body.stokes``, a flat list ``n, m, C_nm, S_nm, ...`` of unnormalised Stokes
  coefficients in the centre-of-mass principal-axis frame.

With a mass model the scenario's normalised inertia is derived: the principal moments divided
by the largest (:attr:`BodySpec.inertia`). A parameter of another kind than ``body.model`` must
keep its default (a value there would be silently unused).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, Mapping

from tumble_ros.core.model.gravity_field import GravityField
from tumble_ros.core.model.limits import ScenarioError
from tumble_ros.core.model.mass_models import (DensityMoments, Ellipsoid, MassModelError,
                                               Polyhedron)
from tumble_ros.core.model.shape_files import load_shape, resolve_shape_path

__all__ = ['BODY_MODELS', 'BodySpec', 'BODY_PARAMETER_DOCS', 'BODY_FIELDS']

#: ``body.model``: ``inertia`` (no mass model) or a mass model of :data:`MASS_MODELS`.
BODY_MODELS = ('inertia', 'ellipsoid', 'polyhedron', 'moments')
#: The fields each kind uses.
BODY_FIELDS = {
    'inertia': (),
    'ellipsoid': ('semi_axes', 'density'),
    'polyhedron': ('shape_file', 'density'),
    'moments': ('mass', 'reference_radius', 'principal_moments', 'stokes'),
}
#: Unit and description of every ``body.*`` parameter (docs/ros.md's table).
BODY_PARAMETER_DOCS = {
    'body.model': ('', 'mass model of the body: inertia (the normalised inertia given), '
                       'ellipsoid, polyhedron or moments'),
    'body.semi_axes': ('km', 'ellipsoid: semi-axes a, b, c along the body x, y, z axes'),
    'body.density': ('kg/m^3', 'ellipsoid, polyhedron: uniform density'),
    'body.shape_file': ('', 'polyhedron: OBJ or vertex/facet counts shape file (absolute, '
                            'relative to the params file, or to share/tumble_ros)'),
    'body.mass': ('kg', 'moments: mass'),
    'body.reference_radius': ('km', 'moments: reference radius of the Stokes coefficients'),
    'body.principal_moments': ('kg km^2', 'moments: principal moments A, B, C'),
    'body.stokes': ('', 'moments: flat list n, m, C_nm, S_nm, ... (unnormalised, principal '
                        'frame)'),
}


@dataclass(frozen=True)
class BodySpec:
    """
    The ``body.*`` parameters, validated; :attr:`mass_model` builds (and caches) the model.

    ``shape_file`` is kept as resolved (an absolute path) so that the scenario's parameters
    name the file that was read.
    """

    model: str = 'inertia'
    semi_axes: tuple[float, ...] = (0.0, 0.0, 0.0)
    density: float = 0.0
    shape_file: str = ''
    mass: float = 0.0
    reference_radius: float = 0.0
    principal_moments: tuple[float, ...] = (0.0, 0.0, 0.0)
    stokes: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if self.model not in BODY_MODELS:
            raise MassModelError(f'body.model: must be one of {list(BODY_MODELS)}, got '
                                 f'{self.model!r}')
        for name in ('density', 'mass', 'reference_radius'):
            value = getattr(self, name)
            if isinstance(value, int) and not isinstance(value, bool):
                object.__setattr__(self, name, float(value))
        for name in ('semi_axes', 'principal_moments', 'stokes'):
            value = getattr(self, name)
            if isinstance(value, (str, bytes)) or not hasattr(value, '__iter__'):
                raise MassModelError(f'body.{name}: must be a list of numbers, got {value!r}')
            object.__setattr__(self, name, tuple(
                float(v) if isinstance(v, int) and not isinstance(v, bool) else v
                for v in value))
        defaults = BodySpec.__dataclass_fields__
        for name, spec in defaults.items():
            if name == 'model' or name in BODY_FIELDS[self.model]:
                continue
            if getattr(self, name) != spec.default:
                raise MassModelError(f'body.{name}: is not used by body.model {self.model} '
                                     f'(used by: {_users(name)}), got {getattr(self, name)!r}')
        _build(self)    # builds and validates

    @property
    def mass_model(self) -> Ellipsoid | Polyhedron | DensityMoments | None:
        """Return the mass model (None for ``inertia``), built once per distinct spec."""
        return _build(self)

    @property
    def inertia(self) -> tuple[float, float, float] | None:
        """Return the normalised principal moments (largest 1), or None for ``inertia``."""
        model = self.mass_model
        if model is None:
            return None
        moments = [float(v) for v in model.principal_moments]
        top = max(moments)
        return (moments[0] / top, moments[1] / top, moments[2] / top)

    def gravity_field(self, degree: int) -> GravityField:
        """Return the mass model's GravityField to ``degree`` (cached), principal frame."""
        if self.mass_model is None:
            raise MassModelError(f'body.model: inertia has no gravity field beyond degree 2, '
                                 f'got degree {degree}')
        return _field(self, degree)

    def to_parameters(self) -> dict[str, Any]:
        """Return the ``body.*`` flat parameters."""
        return {f'body.{name}': (list(getattr(self, name))
                                 if isinstance(getattr(self, name), tuple)
                                 else getattr(self, name))
                for name in BodySpec.__dataclass_fields__}

    @classmethod
    def from_parameters(cls, params: Mapping[str, Any],
                        params_file: str | Path | None = None) -> BodySpec:
        """Build from the ``body.*`` entries of a flat mapping (others ignored)."""
        values = {k.split('.', 1)[1]: v for k, v in params.items() if k.startswith('body.')}
        unknown = sorted(set(values) - set(cls.__dataclass_fields__))
        if unknown:
            raise MassModelError(f'body.{unknown[0]}: unknown body parameter (known: '
                                 f'{", ".join(sorted(BODY_PARAMETER_DOCS))})')
        if values.get('model') == 'polyhedron' and values.get('shape_file'):
            try:
                values['shape_file'] = str(resolve_shape_path(str(values['shape_file']),
                                                              params_file))
            except ScenarioError as exc:
                raise _named(exc) from None
        return cls(**values)


def _users(name: str) -> str:
    return ', '.join(kind for kind, fields in BODY_FIELDS.items() if name in fields)


@lru_cache(maxsize=32)
def _build(spec: BodySpec) -> Ellipsoid | Polyhedron | DensityMoments | None:
    try:
        if spec.model == 'ellipsoid':
            return Ellipsoid(spec.semi_axes, spec.density)  # type: ignore[arg-type]
        if spec.model == 'polyhedron':
            if not spec.shape_file:
                raise MassModelError("shape_file: body.model polyhedron needs one, got ''")
            path = resolve_shape_path(spec.shape_file)
            body = load_shape(path, spec.density)
            return body if body.is_principal else body.in_principal_axes()
        if spec.model == 'moments':
            return DensityMoments.from_parameters(
                {'mass': spec.mass, 'reference_radius': spec.reference_radius,
                 'principal_moments': spec.principal_moments, 'stokes': spec.stokes})
    except ScenarioError as exc:
        raise _named(exc) from None
    return None


@lru_cache(maxsize=32)
def _field(spec: BodySpec, degree: int) -> GravityField:
    model = spec.mass_model
    assert model is not None
    return model.gravity_field(degree)


def _named(exc: ScenarioError) -> MassModelError:
    """Return the error with its field named as the parameter: ``body.<field>``."""
    text = str(exc)
    return MassModelError(text if text.startswith('body.') else f'body.{text}',
                          getattr(exc, 'facet', None))
