"""Design studies shipped as TOML package data (read by ``resources.load_study``; ``isoforce optimize``)."""
