"""``python -m app.cli COMMAND ...``: the command line alone (no desktop app)."""
from app.cli import end_process, main

end_process(main())
