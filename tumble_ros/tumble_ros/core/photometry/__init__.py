"""
tumble_ros.core.photometry: what a telescope sees of the body (ROS-free, numpy).

``shape`` (the body's convex mesh),
``brightness`` (disk-integrated brightness, phase and aspect angles, magnitude), ``lightcurve``
(the Sun and the observer from a scenario's orbit; :func:`synthetic_lightcurve` on a run's
attitudes). docs/analysis.md, "Lightcurves: what a telescope sees". The scattering laws
(S(mu0, mu), a registry) and the ``lightcurve.*`` parameters are inputs of the scenario, in
``core.model.scattering`` and ``core.model.lightcurve_settings``; re-exported here.
"""
from tumble_ros.core.model.lightcurve_settings import LIGHTCURVE_PARAMETER_DOCS, LightcurveSettings
from tumble_ros.core.model.scattering import law, LAWS, ScatteringLaw
from tumble_ros.core.photometry.brightness import (aspect_angles, brightness,
                                                   brightness_in_body, latitude_longitude,
                                                   magnitude, phase_angle,
                                                   reference_brightness, to_body)
from tumble_ros.core.photometry.lightcurve import (lightcurve_mesh, LightcurveRecord,
                                                   LightcurveSampler, observer_geometry,
                                                   ObserverGeometry, synthetic_lightcurve)
from tumble_ros.core.photometry.shape import (body_mesh, convex_mesh, ellipsoid_mesh,
                                              icosphere, Mesh)

__all__ = ['aspect_angles', 'brightness', 'brightness_in_body', 'latitude_longitude',
           'magnitude', 'phase_angle', 'reference_brightness', 'to_body',
           'LIGHTCURVE_PARAMETER_DOCS', 'LightcurveRecord', 'LightcurveSampler',
           'LightcurveSettings', 'lightcurve_mesh', 'observer_geometry', 'ObserverGeometry',
           'synthetic_lightcurve', 'law', 'LAWS', 'ScatteringLaw', 'body_mesh', 'convex_mesh',
           'ellipsoid_mesh', 'icosphere', 'Mesh']
