"""Figures: every function here takes result objects or plain arrays and returns a matplotlib
``Figure`` (:func:`vibrogear.report.figure.new_figure`, no pyplot state); nothing here writes a
file.  One module per verb or kind of figure, named as the verb (``sweep``, ``states``, ``nvh``,
...), plus the figures several verbs share (``branch``, ``bifurcation``, ``housing_surface``).
The writers (:mod:`vibrogear.report.writers`) save them."""
