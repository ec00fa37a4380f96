"""From finished runs to the paper's results.

``reevaluate`` (held-out re-evaluation of a run's final genomes), ``fronts`` (merged Pareto
fronts, selection points, statistical tests), ``report`` (Table 4, Figures 4-6, report.md).
"""
