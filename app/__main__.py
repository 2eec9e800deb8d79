"""``python -m app``: the same as the ``isoforce`` console script."""
import sys

from .launch import main

sys.exit(main())
