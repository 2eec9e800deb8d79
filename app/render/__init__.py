"""The top shared floor: any view (map, pose, workspace, compare, statistics) to a file,
headless, for the command line's ``figure`` and the app's exports (``views``).
"""
