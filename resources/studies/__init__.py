"""Design studies shipped as TOML package data (read by ``metrics.studies``; ``isoforce optimize``)."""
