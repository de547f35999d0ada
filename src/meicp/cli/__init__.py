"""Command-line interface: ``meicp SUBCOMMAND``."""
