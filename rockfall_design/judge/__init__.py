"""The judgement: what the rocks did at the measures, and how sure we are of it.

* :mod:`~rockfall_design.judge.bounds` -- one-sided upper confidence bounds of
  percentiles (order statistics) and of fractions (Clopper-Pearson);
* :mod:`~rockfall_design.judge.outcomes` -- the one place where a rock counts
  as held by a measure, and where the rocks reaching the protected zone are
  counted. ``check`` (the exact run) and the optimiser's screening both judge
  through it;
* :mod:`~rockfall_design.judge.plan` -- the project resolved against its
  plugins (measures placed, safety concept, design section), once per command.
"""
