"""The ``cablelab`` command line (CONTRACT section 5).

Each verb is one module in :mod:`cablelab.commands` with ``HELP``, ``add_arguments(parser)`` and
``run(args) -> int``. User errors (:class:`CablelabError`) print one line on stderr and exit 2;
with ``--json`` nothing but the one JSON object goes to stdout.
"""
from __future__ import annotations

import argparse
import errno
import importlib
import os
import sys

from .errors import CablelabError

#: verb -> module under cablelab.commands
VERBS = {
    "estimate": "estimate",
    "compare": "compare",
    "diagnose": "diagnose",
    "identify": "identify",
    "report": "report",
    "import": "import_",
    "record": "record",
    "replay": "replay",
    "info": "info",
    "repair": "repair",
    "batch": "batch",
    "layout": "layout",
    "excite": "excite",
    "new-plant": "new_plant",
}


class OneLineParser(argparse.ArgumentParser):
    """Usage errors as one line naming the option (CONTRACT: one line, exit 2), with a pointer
    to ``--help`` instead of the multi-line usage block."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def defer(self, add) -> None:
        """Call ``add(self)`` just before this parser parses: options that cost an import to know
        (the plants' own, :func:`cablelab.commands._workbench_args.add_plant_options`) are only
        looked up for the verb being run (its ``--help`` included), not for every verb."""
        self._deferred = [*getattr(self, "_deferred", ()), add]

    def parse_known_args(self, args=None, namespace=None):
        deferred, self._deferred = getattr(self, "_deferred", ()), []
        for add in deferred:
            add(self)
        return super().parse_known_args(args, namespace)


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="cablelab",
        description="Compare cable-robot and crane models with measurements, find the missing "
        "physical effect, add it and watch the error fall. Every verb reads a rosbag2 directory "
        "(or its .mcap file) and the /plant_description in it unless --description is given.",
    )
    sub = parser.add_subparsers(dest="verb", metavar="VERB", parser_class=OneLineParser)
    for verb, module in VERBS.items():
        mod = importlib.import_module(f"cablelab.commands.{module}")
        p = sub.add_parser(verb, help=mod.HELP, description=getattr(mod, "DESCRIPTION", mod.HELP))
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 2
    try:
        return int(args._run(args) or 0)
    except CablelabError as exc:
        line = " ".join(str(exc).split())   # one line, whatever the message's source wrapped
        print(f"cablelab {args.verb}: error: {line}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"cablelab {args.verb}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into e.g. head: stop quietly
        with _suppress_os():
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:  # the machine, not the program: disk full, read-only, permission
        if exc.errno not in _ENVIRONMENT_ERRNOS:
            raise
        from .atomic import os_error_message

        print(f"cablelab {args.verb}: error: {os_error_message(exc.filename or '?', exc)}", file=sys.stderr)
        return 2
    finally:   # the verb's output locks end with the verb (also when main runs in-process)
        from .atomic import release_all

        release_all()


_ENVIRONMENT_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM}


def _suppress_os():
    import contextlib

    return contextlib.suppress(OSError)


if __name__ == "__main__":
    sys.exit(main())
