"""
Integrating a scenario in time.

The propagator (segments split at impacts), batch runs, ensembles of bodies (the time base is
the model's: ``core.model.timebase``).
"""
