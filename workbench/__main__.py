"""``python -m workbench`` runs the command line (same as ``vr-workbench``)."""

import sys

from workbench.cli import main

sys.exit(main())
