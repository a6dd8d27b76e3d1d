"""design/: CFA search on top of the study: layouts (symmetry-folded
enumeration), filter spectra (parametric or a set's), a fast proxy, the
search engines (exhaustive, pymoo NSGA-II), the full chain through the
study's runner, the Pareto front with intervals, and design.html.

Nothing imports design/ but ``cfa_mitsuba.commands.design``.
"""
