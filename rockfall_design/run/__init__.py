"""The run: project -> engine -> statistics.

The step between a validated project and the judge: the engine's inputs
drawn from the project (:mod:`.releases`), the ensemble run and its per-rock
and per-station statistics (:mod:`.simulation`), runs too large to keep,
accumulated chunk by chunk (:mod:`.streamed`, :mod:`.histograms`), which
rocks reach a station (:mod:`.reach`), the rocks passing a station or a
barrier (:mod:`.passages`) and the JSON summary of a run (:mod:`.summary`).
A run here is one simulation (:class:`~.simulation.SimulationRun`,
:class:`~.streamed.StreamedRun`); a parametric study of many runs is
:mod:`rockfall_design.studies`. Nothing here imports the judge, the optimiser or the
commands.
"""
