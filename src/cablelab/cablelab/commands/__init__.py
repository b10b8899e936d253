"""One module per ``cablelab`` verb: ``HELP``, ``add_arguments(parser)``, ``run(args) -> int``."""
