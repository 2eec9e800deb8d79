"""Reproductions and benchmarks, run from the repository root; ``paper_data`` holds the papers' printed numbers."""
