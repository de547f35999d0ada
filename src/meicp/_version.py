"""The version of meicp: its own module, so that what reports it (``info``, the files it
writes) needs nothing above it; ``pyproject.toml`` reads it from here."""

__version__ = "0.1.0"
