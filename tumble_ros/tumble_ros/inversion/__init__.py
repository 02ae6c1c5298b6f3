"""
From photometry back to the spin state: the tumbler inversion (ROS-free).

The layer sits above ``analysis`` (its period search and plots) and below ``cli``:
:mod:`.campaign` is the one type every reader returns and the fit takes (times, magnitudes,
errors, the Sun's and the observer's vectors, lightcurve blocks); docs/inversion.md.
"""
