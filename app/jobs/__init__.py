"""The jobs floor: background work and what it returns, with no Qt.

``runner`` (``JobRunner``: one worker thread, cancellation by tag), ``map_worker`` (the coarse
maps' worker process), ``requests`` (the map and study jobs: ``MapRequest`` in, one frozen
``MapResult`` out) and ``heap`` (freed heap handed back after each full map).
"""
