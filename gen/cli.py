"""The ``npstereo`` command line.

Each subcommand lives in its own module of this package exposing ``add_parser(subparsers)``
and ``run(args)``. Every expected failure (bad parameter, unreadable file) is raised as a
:class:`~npstereo.golden.params.UserError` and printed here as
one line, exit code 2, no traceback.
"""

import argparse
import importlib
import sys

from ..golden.params import UserError

__all__ = ["main", "UsageError"]

#: Subcommand modules, in the order ``npstereo --help`` lists them.
COMMANDS = ["match", "eval", "paper", "demo", "verilog", "cosim", "report"]


class UsageError(UserError):
    """A malformed command line."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(f"{self.prog}: {message}")


def build_parser():
    parser = _Parser(prog="npstereo", description=(
        "Generate and verify FPGA stereo-matching cores (Ambrosch et al. 2008)."))
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name in COMMANDS:
        importlib.import_module(f"{__package__}.cmd_{name}").add_parser(subparsers)
    return parser


def main(argv=None):
    try:
        args = build_parser().parse_args(argv)
        return args.run(args) or 0
    except UserError as error:
        print(f"npstereo: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("npstereo: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
