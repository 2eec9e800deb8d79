"""``python -m app.cli COMMAND ...``: the command line alone (no desktop app)."""
import sys

from app.cli import main

sys.exit(main())
