"""The numpy reference of the step: sensing (``sensing``) and the team heuristics (``heuristics``).

Selected with ``WorldConfig(kernel="numpy")`` (``NumpySimulation``); slower than the compiled
path (``gathering_env.compiled``) and kept as the readable definition the tests compare it with.
"""
