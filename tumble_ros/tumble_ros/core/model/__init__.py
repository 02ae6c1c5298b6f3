"""
The body and its inputs: validated scenarios, shapes, spin states, rotations, the time base.

Also the equations of motion and their invariants, the limits of accepted input, the user's
files read safely (``user_files``), the surface's scattering laws and what a synthetic lightcurve
assumes (``scattering``, ``lightcurve_settings``: inputs of the scenario). Above ``torques``,
``kernels`` and ``integrators`` (the scenario names their settings), below ``photometry`` and
``propagation`` (they take a scenario).
"""
