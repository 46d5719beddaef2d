"""Trial placements: measures placed by hand in the browser app, judged at once.

A room of its own, between the public face (:mod:`rockfall_design.api`) and
the rooms it draws on. The optimiser searches for the least-cost design; a
trial judges the measures an engineer places by hand, from the optimiser's
screening table (:class:`~rockfall_design.optimiser.screening.Screening`),
through the judgement of :mod:`rockfall_design.judge` on rocks run by
:mod:`rockfall_design.run`. It imports the optimiser and is imported by
nothing but :mod:`rockfall_design.api` (and, for types, :mod:`rockfall_design.serve`),
so it can live neither inside the optimiser (whose job it is not) nor in
``studies/`` (which the optimiser imports: that would close a circle).

:mod:`~rockfall_design.trial.placements` holds the trial run and its
placements; the front end reaches them through
:func:`rockfall_design.api.trial_run`.
"""
