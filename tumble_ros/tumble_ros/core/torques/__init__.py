"""
The torques on the body, as components the integrators add up.

* :mod:`.gravity_gradient`: the Sun's tidal torque in a circular orbit (built in);
* :mod:`.pulses`: the impact pulses (built in, a constant torque per segment);
* :mod:`.component`: :class:`TorqueComponent`, any other torque, defined outside core with
  :func:`torque_function` and run by every integrator unchanged.

The kernels' :func:`~tumble_ros.core.kernels.physics.body_torque` is their sum, the one place
that knows the total torque.
"""
from tumble_ros.core.torques.component import (extra_torque_arrays, NO_EXTRA, torque_function,
                                               TorqueComponent)
from tumble_ros.core.torques.frames import orbital_to_body
from tumble_ros.core.torques.gravity_gradient import (gravity_gradient_potential,
                                                      gravity_gradient_torque, sun_direction_body,
                                                      sun_direction_orbital, tidal_coefficients,
                                                      tidal_potential_coefficient, tidal_torque)
from tumble_ros.core.torques.pulses import pulse_torque

__all__ = ['TorqueComponent', 'torque_function', 'extra_torque_arrays', 'NO_EXTRA',
           'orbital_to_body', 'gravity_gradient_potential', 'gravity_gradient_torque',
           'sun_direction_body', 'sun_direction_orbital', 'tidal_coefficients', 'tidal_torque',
           'tidal_potential_coefficient', 'pulse_torque']
