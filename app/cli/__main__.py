"""``python -m app.cli COMMAND ...``: the command line alone (no desktop app)."""
import sys

from . import main

sys.exit(main())
