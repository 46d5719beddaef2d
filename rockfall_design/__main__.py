"""``python -m rockfall_design`` runs the command line."""

import sys

from .cli.program import main

sys.exit(main())
