"""The undo history of design edits, in plain Python: a ``Design`` before and after each step.

A step is one user edit of the design: a spin box, a choice, a whole slider drag (from press
to release: ``History.record(..., merge=True)`` extends the open step instead of adding one),
a device switch, a loaded file or a study's design. ``AppModel`` (``app.gui.model``) records
every change of its preset or mechanism here and applies ``undo``/``redo``'s design back; the
menus show ``undo_text``/``redo_text``, e.g. "gear_ratios 6.875 -> 13.75". No Qt: it is tested
without a display, as QUndoStack's clean index and merging are reimplemented in a few lines.

``saved`` is the design last loaded or saved: ``modified(design)`` says whether a design would
be lost on close, and an undo back to it clears the mark, as desktop apps do.
"""
from __future__ import annotations

from dataclasses import dataclass

from app.logic.design_changes import _change_text, _same, parameter_changes
from kinematics.contract import Mechanism
from resources import Preset

#: Steps kept; the oldest go first.
HISTORY_LIMIT = 500


@dataclass(frozen=True)
class Design:
    """What the undo history holds: the device (preset) and its current parameters."""

    preset: Preset
    mechanism: Mechanism

    def same(self, other: Design | None) -> bool:
        """The same device (the same preset object) and equal parameters."""
        return other is not None and self.preset is other.preset and self.mechanism == other.mechanism


def preset_label(preset: Preset) -> str:
    """A device as the menus name it: its name, with the file's name for a TOML file's."""
    source = str(preset.source or "")
    name = preset.name or preset.key
    if source.endswith(".toml") and ("/" in source or "\\" in source):
        return f"{name} ({source.replace(chr(92), '/').rsplit('/', 1)[-1]})"
    return name


def edit_label(before: Design, after: Design) -> str:
    """A step in words, display units: ``"gear_ratios 6.875 -> 13.75 (theta_0)"`` (only the entry
    of a vector that changed, when one did, named after the values), ``"proximal_length 140 -> 150 mm"``,
    ``"device Inverse3 prototype -> Falcon"``, or ``"no change"``.

    >>> from resources import load_preset
    >>> p = load_preset("fivebar_singh")
    >>> edit_label(Design(p, p.mechanism), Design(p, p.mechanism.replace_display(gear_ratios=(12.0, 10.0))))
    'gear_ratios 10 -> 12 (theta_1)'
    """
    if before.preset is not after.preset:
        changed = (parameter_changes(after.preset.mechanism, after.mechanism)
                   if type(after.preset.mechanism) is type(after.mechanism) else [])
        return (f"device {preset_label(before.preset)} -> {preset_label(after.preset)}"
                + (f" ({'; '.join(changed)})" if changed else ""))
    if type(before.mechanism) is not type(after.mechanism):
        return "; ".join(parameter_changes(before.mechanism, after.mechanism))
    old_table = {info.name: v for info, v in before.mechanism.parameter_table()}
    phrases = []
    for info, value in after.mechanism.parameter_table():
        old = old_table[info.name]
        if _same(old, value):
            continue
        unit = f" {info.unit}" if info.unit else ""
        entries = [i for i, (a, b) in enumerate(zip(old, value)) if not _same(a, b)] if isinstance(value, tuple) else []
        if len(entries) == 1 and len(old) == len(value):
            i = entries[0]
            labels = tuple(info.labels or ())
            phrases.append(f"{info.name} {_change_text(old[i], value[i])}{unit}"
                           + (f" ({labels[i]})" if i < len(labels) else f" (entry {i + 1})"))
        else:
            phrases.append(f"{info.name} {_change_text(old, value)}{unit}")
    return "; ".join(phrases) if phrases else "no change"


@dataclass
class Step:
    """One undoable edit: the design before and after it; ``open`` while a slider drag extends it."""

    before: Design
    after: Design
    open: bool = False

    @property
    def label(self) -> str:
        return edit_label(self.before, self.after)


class History:
    """Undo and redo stacks of ``Step``\\ s and the design last saved (see the module docstring)."""

    def __init__(self, saved: Design | None = None, limit: int = HISTORY_LIMIT) -> None:
        self.undo_steps: list[Step] = []
        self.redo_steps: list[Step] = []
        self.saved = saved
        self.limit = int(limit)

    # -- recording ---------------------------------------------------------------------
    def record(self, before: Design, after: Design, *, merge: bool = False) -> None:
        """A new step from ``before`` to ``after`` (the redo stack is dropped, as in every editor).

        ``merge`` (a slider still held): the open step, if any, is extended to ``after`` and
        stays open; else a new open step starts. ``close`` ends it (the slider released).
        """
        if before.same(after):
            return
        top = self.undo_steps[-1] if self.undo_steps else None
        if merge and top is not None and top.open:
            top.after = after
        else:
            self.close()
            self.undo_steps.append(Step(before, after, open=merge))
            del self.undo_steps[:-self.limit]
        self.redo_steps.clear()
        if self.undo_steps[-1].before.same(self.undo_steps[-1].after):
            self.undo_steps.pop()           # a drag back to where it started: no step at all

    def close(self) -> None:
        """End the open step (a slider released): the next edit is a step of its own."""
        if self.undo_steps:
            self.undo_steps[-1].open = False

    # -- undo and redo -----------------------------------------------------------------
    def can_undo(self) -> bool:
        return bool(self.undo_steps)

    def can_redo(self) -> bool:
        return bool(self.redo_steps)

    def undo_text(self) -> str | None:
        """The step ``undo`` would take back, in words; None if there is none."""
        return self.undo_steps[-1].label if self.undo_steps else None

    def redo_text(self) -> str | None:
        return self.redo_steps[-1].label if self.redo_steps else None

    def undo(self) -> Design:
        """Take back the last step; returns the design to show (its ``before``)."""
        if not self.undo_steps:
            raise IndexError("nothing to undo")
        step = self.undo_steps.pop()
        step.open = False
        self.redo_steps.append(step)
        return step.before

    def redo(self) -> Design:
        """Do the last undone step again; returns the design to show (its ``after``)."""
        if not self.redo_steps:
            raise IndexError("nothing to redo")
        step = self.redo_steps.pop()
        self.undo_steps.append(step)
        return step.after

    def rebase(self, old: Preset, new: Preset) -> None:
        """Every step and the saved design that name ``old`` name ``new`` instead: the same device
        with another map range (View > Fit map to workspace), not an edit of its own."""
        def moved(design: Design | None) -> Design | None:
            return Design(new, design.mechanism) if design is not None and design.preset is old else design
        for step in (*self.undo_steps, *self.redo_steps):
            step.before, step.after = moved(step.before), moved(step.after)
        self.saved = moved(self.saved)

    # -- saved -------------------------------------------------------------------------
    def mark_saved(self, design: Design) -> None:
        """``design`` is on disk (saved, or just loaded): not modified."""
        self.saved = design

    def modified(self, design: Design) -> bool:
        """Whether ``design`` differs from the one last saved or loaded."""
        return not design.same(self.saved)
