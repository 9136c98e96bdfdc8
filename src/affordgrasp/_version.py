"""The package's version, stamped into what it writes (datasets, models, reports, viewers)."""

__version__ = "0.1.0"
