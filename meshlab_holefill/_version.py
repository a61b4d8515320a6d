"""The package version (one place, read by the package and by written scripts)."""
__version__ = "0.1.0"
