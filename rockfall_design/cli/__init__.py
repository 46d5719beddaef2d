"""The command room: every ``rockfall-design`` command, and only commands.

Each command turns its arguments into calls of the API, prints and writes
what they return, and maps errors to exit codes (:mod:`.program`, the only
place that does). Among the package's rooms it imports only the API, the
results, the report, the errors and the project (and the light
``limits`` and ``version``); the exceptions: ``plugins.check_blocked_names``
in :mod:`.program` (the API would load numba for ``--help``), the figure names
of the calibration and the study, and ``serve``, the other front end. Files:

* :mod:`.program`: ``main``, the table of which module runs each command
  (imported when the command is chosen), signals and exit codes;
* :mod:`.parsers`: every command's parser, light (``--help`` imports no
  engine, numba, scipy, pandas or matplotlib);
* :mod:`.options`: the options commands share;
* :mod:`.common`: what every command does around its run (plugins,
  progress, memory guard, files reserved, figures and report);
* :mod:`.section_commands`: ``simulate``, ``check``, ``optimise``,
  ``plugins`` and ``serve`` on one project;
* :mod:`.optimise_outputs`: what ``optimise`` writes and prints for one
  project or one section of a corridor;
* :mod:`.scenario_commands`: ``check --scenarios`` and the optimiser's
  scenario report;
* :mod:`.corridor_commands`: every command over the sections of a corridor,
  with what they print in total (:mod:`.corridor_report`) and the design
  back on the map (:mod:`.corridor_map`);
* :mod:`.study_command`, :mod:`.calibrate_command`, :mod:`.terrain_command`:
  ``study``, ``calibrate`` and ``compare``, ``section``.
"""

from .program import main

__all__ = ["main"]
