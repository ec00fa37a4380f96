"""The production step: numba kernels (``kernels``) and the W-world engine around pymunk (``engine``).

Every part of a step but pymunk's own calls runs here, compiled; ``gathering_env.reference``
computes the same step in plain numpy, and the tests hold the two to identical episodes.
"""
