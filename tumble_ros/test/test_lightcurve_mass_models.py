"""
The lightcurve of a body given by its mass model: the shape seen is the mass model's shape.

A scenario with ``body.model`` ellipsoid or polyhedron shows that body to the telescope
(``core.photometry.lightcurve.lightcurve_mesh``), not the ellipsoid of its normalised moments;
a non-convex polyhedron is refused a lightcurve, with the reason (self-shadowing is not
modelled).
"""
import numpy as np
import pytest

from tumble_ros.core import Scenario, ScenarioError, simulate
from tumble_ros.core.model.body import BodySpec
from tumble_ros.core.model.mass_models import Polyhedron
from tumble_ros.core.photometry import brightness, convex_mesh, ellipsoid_mesh
from tumble_ros.core.photometry.lightcurve import (lightcurve_mesh, LightcurveSampler,
                                                   LightcurveSettings, synthetic_lightcurve)

#: A tumbler under the Sun's torque (rad/yr): a lightcurve with both periods in it.
SPIN = {'orbit_rate': 1.0, 'omega0': (3.0, 1.0, 30.0), 'euler0': (0.5, 0.2, 0.7),
        'duration': 0.3, 'output_interval': 0.001}


def _run(body: BodySpec) -> tuple[Scenario, np.ndarray, np.ndarray]:
    scenario = Scenario(body=body, **SPIN)
    result = simulate(scenario)
    return scenario, result.t, result.quaternion


def test_an_ellipsoid_mass_model_is_seen_as_its_semi_axes_and_as_its_moments_ellipsoid():
    """
    The ellipsoid's own mesh, and the same magnitudes as the ellipsoid of its moments.

    A homogeneous ellipsoid's principal moments give back its semi-axes' proportions
    (core/model/shape.py), and magnitudes do not depend on the body's size: the two
    independent routes agree to rounding, at every sample.
    """
    axes = (0.23, 0.19, 0.15)
    body = BodySpec(model='ellipsoid', semi_axes=axes, density=2600.0)
    scenario, t, q = _run(body)
    mesh = lightcurve_mesh(scenario, scenario.lightcurve)
    reference = ellipsoid_mesh(axes, scenario.lightcurve.subdivisions)
    np.testing.assert_array_equal(mesh.vertices, reference.vertices)
    from_model = synthetic_lightcurve(scenario, t, q)
    from_moments = synthetic_lightcurve(Scenario(inertia=scenario.inertia, **SPIN), t, q)
    np.testing.assert_allclose(from_model.magnitude, from_moments.magnitude, rtol=0, atol=1e-9)
    assert np.ptp(from_model.magnitude) > 0.1     # a lightcurve, not a constant


def test_a_polyhedron_is_seen_as_its_own_facets():
    """The shipped Apophis polyhedron: its 320 facets are the mesh, and they are what is seen."""
    body = BodySpec(model='polyhedron', density=2600.0, shape_file='config/shapes/apophis.obj')
    scenario, t, q = _run(body)
    model = body.mass_model
    assert isinstance(model, Polyhedron) and model.convex
    mesh = lightcurve_mesh(scenario, scenario.lightcurve)
    assert len(mesh.areas) == len(model.facets) == 320
    sampler = LightcurveSampler.of(scenario)
    assert sampler is not None
    record = sampler(t, q)
    own = convex_mesh(model.vertices, model.facets)
    sun = record_sun(scenario, t)
    direct = brightness(q, sun, sun, own, scenario.lightcurve.law)
    np.testing.assert_allclose(record.brightness, direct, rtol=1e-12)
    # ... and it differs from the ellipsoid of the same moments by its facets: a little
    ellipsoid = synthetic_lightcurve(scenario.replace(body=BodySpec()), t, q)
    difference = np.abs(record.magnitude - ellipsoid.magnitude)
    assert 1e-4 < difference.max() < 0.2


def record_sun(scenario: Scenario, t: np.ndarray) -> np.ndarray:
    """Return the circular orbit's Sun direction, orbital frame (the default observer's too)."""
    angle = scenario.orbit_rate * t
    return np.stack([np.sin(angle), np.cos(angle), np.zeros_like(angle)], axis=-1)


def test_a_non_convex_polyhedron_is_refused_a_lightcurve_with_the_reason(tmp_path):
    """
    A cube with a dent in one face: a body that shadows itself is refused a lightcurve.

    It had none, silently (LightcurveSampler.of returned None): the scenario now says why, and
    runs with ``lightcurve.enabled`` false.
    """
    dented = tmp_path / 'dented.obj'
    lines = ['v -1 -1 -1', 'v 1 -1 -1', 'v 1 1 -1', 'v -1 1 -1',
             'v -1 -1 1', 'v 1 -1 1', 'v 1 1 1', 'v -1 1 1', 'v 0 0 0.5']
    # the top face (z = 1) is four triangles meeting at a vertex pushed inwards
    faces = ['f 1 3 2', 'f 1 4 3', 'f 1 2 6', 'f 1 6 5', 'f 2 3 7', 'f 2 7 6',
             'f 3 4 8', 'f 3 8 7', 'f 4 1 5', 'f 4 5 8',
             'f 5 6 9', 'f 6 7 9', 'f 7 8 9', 'f 8 5 9']
    dented.write_text('\n'.join(lines + faces) + '\n')
    body = BodySpec(model='polyhedron', density=2600.0, shape_file=str(dented))
    model = body.mass_model
    assert isinstance(model, Polyhedron) and not model.convex
    with pytest.raises(ScenarioError,
                       match=r'lightcurve.enabled: the polyhedron of body.shape_file '
                       r'.*dented.obj is not convex \(vertex 5 lies 0.894 .* outside the plane of '
                       r'its neighbouring facet .*set lightcurve.enabled: false'):
        Scenario(body=body, **SPIN)
    scenario = Scenario(body=body, lightcurve=LightcurveSettings(enabled=False), **SPIN)
    assert LightcurveSampler.of(scenario) is None
    with pytest.raises(ValueError, match='not convex'):
        lightcurve_mesh(scenario, LightcurveSettings())
