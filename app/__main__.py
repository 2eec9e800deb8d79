"""``python -m app``: the same as the ``isoforce`` console script."""
import sys

from .cli import main

sys.exit(main())
