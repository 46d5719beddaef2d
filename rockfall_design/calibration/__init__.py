"""Calibration: fit ground parameters to observed stop positions, and say how sure the fit is.

- :mod:`.observations`: the observed-stops CSV, read and checked (one line
  per problem, at its file, line and column);
- :mod:`.sets`: the observation sets (stops, passing heights, ... on every
  profile) a calibration fits;
- :mod:`.distances`: energy / Wasserstein-1 distance of stop positions, the
  level shares with their Wilson intervals, the fit statistics;
- :mod:`.terms`: the objective's terms, one per observation set, summed with
  weights;
- :mod:`.prior`: the literature's ranges as the prior of a regularised fit;
- :mod:`.screen`: the quick screen before ``fit: auto`` that leaves out what
  moves the criterion by less than its noise;
- :mod:`.fit`: one fit with common random numbers (a Latin hypercube, then
  Nelder-Mead);
- :mod:`.uncertainty`: the bootstrap replicates (each a refit with its own
  seed), the intervals, the correlation, the identification flag;
- :mod:`.procedure`: a calibration or a comparison, the replicates run as
  tasks (locally or on Dask, with the same numbers); not ``run.py``, which
  would read as the package's :mod:`rockfall_design.run` room;
- :mod:`.calibration_result`: :class:`~.calibration_result.CalibrationResult`
  and :class:`~.calibration_result.ComparisonResult` (JSON, tables, the
  calibrated project, figures, terminal);
- :mod:`.document`: their report (report.html and report.md);
- :mod:`.charts`: the stops' ECDF and histogram, the bootstrap cloud (not
  ``figures.py``: :mod:`rockfall_design.report.figures` has that name);
- :mod:`~rockfall_design.cli.calibrate_command`: the ``rockfall-design
  calibrate`` and ``compare`` commands.

The engineer's entry points are :func:`rockfall_design.calibrate` and
:func:`rockfall_design.compare`; the method is described in docs/calibration.md.
"""
