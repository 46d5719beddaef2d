"""The command room: every ``rockfall-design`` command, and only commands.

Each command turns its arguments into calls of the API, prints and writes
what they return, and maps errors to exit codes (:mod:`.main`, the only
place that does). Files:

* :mod:`.program`: ``main``, the parser's dispatch, signals and exit codes;
* :mod:`.options`: the argument parser and the options commands share;
* :mod:`.common`: what every command does around its run (plugins,
  progress, memory guard, files reserved, figures and report);
* :mod:`.section_commands`: ``simulate``, ``check``, ``optimise``,
  ``plugins`` and ``serve`` on one project;
* :mod:`.scenario_commands`: ``check --scenarios`` and the optimiser's
  scenario report;
* :mod:`.corridor_commands`: every command over the sections of a corridor;
* :mod:`.study_command`, :mod:`.calibrate_command`: ``study``,
  ``calibrate`` and ``compare``.
"""

from .program import main

__all__ = ["main"]
