"""Subcommands of the ``affordgrasp`` CLI, one module each (see ``affordgrasp.cli``)."""
