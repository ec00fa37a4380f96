"""How a generation is bred from the last.

``breeding`` (the routine the single- and multi-objective arms share: truncation, one variation
operator per offspring; SO selection), ``operators`` (the genome class with its variation
operators), ``mods`` (NEAT-MODS multi-objective reproduction), ``pareto``
(non-dominated sorting and crowding distance).
"""
