"""``docs/architecture.md`` names every module of the packages, in the row of its folder.

The map of the house stays true: a module added, moved or renamed without its line in the
table "What lives where" fails here, naming the module and the row it belongs in.
"""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("kinematics", "metrics", "resources", "app")
#: Package entry points that are not modules a reader looks for.
SKIPPED = {"__init__.py", "__main__.py"}


def table_rows(text: str) -> dict[str, str]:
    """``{folder: row text}`` of the table under "What lives where" (a folder like ``app/gui/views/``)."""
    section = text.split("## What lives where", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        m = re.match(r"^\|\s*`([\w/]+/)`\s*\|(.*)\|\s*$", line)
        if m:
            rows[m.group(1)] = m.group(2)
    return rows


def test_every_module_is_in_its_folders_row():
    rows = table_rows((ROOT / "docs" / "architecture.md").read_text(encoding="utf-8"))
    missing = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            if path.name in SKIPPED or "__pycache__" in path.parts:
                continue
            folder = path.parent.relative_to(ROOT).as_posix() + "/"
            row = rows.get(folder)
            if row is None:
                missing.append(f"{folder} (no row for the folder)")
            elif f"`{path.name}`" not in row and not re.search(rf"`{re.escape(path.stem)}\.py\b", row):
                missing.append(f"{folder}{path.name}")
    assert not missing, "docs/architecture.md's table misses:\n" + "\n".join(sorted(set(missing)))


def test_the_check_reads_the_table():
    rows = table_rows("# t\n## What lives where\n\n| package | key modules |\n|---|---|\n"
                      "| `kinematics/` | `base.py` (defaults), `grid.py` |\n\n## Next\n| `app/` | `x.py` |\n")
    assert list(rows) == ["kinematics/"] and "`grid.py`" in rows["kinematics/"]
