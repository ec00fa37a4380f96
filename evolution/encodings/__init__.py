"""Genomes and what they decode into: a team's controller and sensor morphology.

``genome`` (the CPPN genome of HyperNEAT-M), ``substrate`` (the HyperNEAT-M substrate and its
decoding), ``direct`` (NEAT-M: a direct encoding with sensor genes), ``controller`` (the batched
feed-forward team controller both decode into).
"""
