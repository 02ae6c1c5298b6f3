"""
The compile machinery of core: how its numerics are compiled, apart from what they compute.

``jit`` (the numba switch, its options and the one cache stamp of every compiled source),
``numba_inlining`` and ``numba_blas_check`` (the two adjustments of numba it makes at import),
``user_cache`` (this package's folder in the user's cache, where the compiled loops are kept).
The numerics (``torques``, ``kernels``, ...) import this room; it imports nothing of core.
"""
