"""Calibration: fit ground parameters to observed stop positions, and say how sure the fit is.

- :mod:`.observations`: the observed-stops CSV, read and checked (one line
  per problem, at its file, line and column);
- :mod:`.distances`: energy / Wasserstein-1 distance of stop positions, the
  level shares with their Wilson intervals, the fit statistics;
- :mod:`.fit`: one fit with common random numbers (a Latin hypercube, then
  Nelder-Mead);
- :mod:`.uncertainty`: the bootstrap replicates (each a refit with its own
  seed), the intervals, the correlation, the identification flag;
- :mod:`.procedure`: a calibration or a comparison, the replicates run as tasks
  (locally or on Dask, with the same numbers);
- :mod:`.calibrated`: :class:`~.calibrated.CalibrationResult` and
  :class:`~.calibrated.ComparisonResult`
  (JSON, tables, the calibrated project, figures, terminal);
- :mod:`.charts`: the stops' ECDF and histogram, the bootstrap cloud;
- :mod:`~rockfall_design.cli.calibrate_command`: the ``rockfall-design
  calibrate`` and ``compare`` commands.

The engineer's entry points are :func:`rockfall_design.calibrate` and
:func:`rockfall_design.compare`; the method is described in docs/calibration.md.
"""
