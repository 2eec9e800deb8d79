"""``python -m app``: the same as the ``isoforce`` console script."""
import sys

from app.launch import main

sys.exit(main())
