"""
tumble_ros.core.photometry: what a telescope sees of the body (ROS-free, numpy).

``shape`` (the body's convex mesh), ``scattering`` (the laws S(mu0, mu), a registry),
``settings`` (the ``lightcurve.*`` parameters),
``brightness`` (disk-integrated brightness, phase and aspect angles, magnitude), ``lightcurve``
(the Sun and the observer from a scenario's orbit; :func:`synthetic_lightcurve` on a run's
attitudes). docs/analysis.md, "Lightcurves: what a telescope sees".
"""
from tumble_ros.core.photometry.brightness import (aspect_angles, brightness,
                                                   brightness_in_body, latitude_longitude,
                                                   magnitude, phase_angle,
                                                   reference_brightness, to_body)
from tumble_ros.core.photometry.lightcurve import (lightcurve_mesh, LightcurveRecord,
                                                   LightcurveSampler, observer_geometry,
                                                   ObserverGeometry, synthetic_lightcurve)
from tumble_ros.core.photometry.scattering import law, LAWS, ScatteringLaw
from tumble_ros.core.photometry.settings import LIGHTCURVE_PARAMETER_DOCS, LightcurveSettings
from tumble_ros.core.photometry.shape import (body_mesh, convex_mesh, ellipsoid_mesh,
                                              icosphere, Mesh)

__all__ = ['aspect_angles', 'brightness', 'brightness_in_body', 'latitude_longitude',
           'magnitude', 'phase_angle', 'reference_brightness', 'to_body',
           'LIGHTCURVE_PARAMETER_DOCS', 'LightcurveRecord', 'LightcurveSampler',
           'LightcurveSettings', 'lightcurve_mesh', 'observer_geometry', 'ObserverGeometry',
           'synthetic_lightcurve', 'law', 'LAWS', 'ScatteringLaw', 'body_mesh', 'convex_mesh',
           'ellipsoid_mesh', 'icosphere', 'Mesh']
