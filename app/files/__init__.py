"""The file floor: atomic writes, figure suffixes, the map and statistics files.

Every writer in the app goes through ``export.atomic_write``, so a failed or interrupted
export leaves no file. Draws nothing: no matplotlib, PyVista or Qt.
"""
