"""The run: project -> engine -> statistics.

The step between a validated project and the judge: the engine's inputs
drawn from the project (:mod:`.releases`), the ensemble run and its per-rock
and per-station statistics (:mod:`.simulation`), runs too large to keep,
accumulated chunk by chunk (:mod:`.streamed`, :mod:`.histograms`), which
rocks reach a station (:mod:`.reach`) and the JSON summary of a run
(:mod:`.summary`). Nothing here imports the judge, the optimiser or the
commands.
"""
