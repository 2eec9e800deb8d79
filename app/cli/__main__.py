"""``python -m app.cli COMMAND ...``: the command line alone (no desktop app), in a process of its own."""
from app.cli._process import end_process, start_up_without_collections

start_up_without_collections()

# (``app.cli`` itself is imported by the line above, before the collector is off; it imports no
# numpy: ``_usage``. What ``main`` imports runs with the collector off.)
from app.cli import main  # noqa: E402

end_process(main())
