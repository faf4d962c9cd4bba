"""Virtual experiments (E01-E12 of docs/experiments.md), one file per family."""
