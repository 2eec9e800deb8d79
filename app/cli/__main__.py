"""``python -m app.cli COMMAND ...``: the command line alone (no desktop app), in a process of its own."""
from app.cli._process import end_process, start_up_without_collections

start_up_without_collections()

from app.cli import main  # noqa: E402  (after the collector is off: its imports are the start-up's)

end_process(main())
