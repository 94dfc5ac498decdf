"""The package version, in one place (read by the CLI's ``--version`` and written into results)."""

__version__ = "0.2.0"
