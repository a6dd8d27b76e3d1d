"""The package version (a leaf: importing it pulls in no stage)."""

__version__ = "0.1.0"
