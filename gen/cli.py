"""The ``npstereo`` command line.

Each subcommand lives in its own module of this package exposing ``add_parser(subparsers)``
and ``run(args)``. Only the module of the command being run is imported: the commands
pull in very different libraries (the golden model, Amaranth, cocotb, matplotlib), and
``npstereo match`` should not wait for the hardware tool chain to load. Every expected
failure (bad parameter, unreadable file) is raised as a
:class:`~npstereo.params.UserError` and printed here as one line, exit code 2, no
traceback.
"""

import argparse
import importlib
import sys

from ..params import UserError

__all__ = ["main", "UsageError", "build_parser"]

#: Subcommand modules, in the order ``npstereo --help`` lists them.
COMMANDS = ["match", "eval", "paper", "demo", "verilog", "cosim", "report", "explore"]


class UsageError(UserError):
    """A malformed command line."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(f"{self.prog}: {message}")


def build_parser(command=None):
    """The parser of every command, or only of ``command`` (which then must be given)."""
    parser = _Parser(prog="npstereo", description=(
        "Generate and verify FPGA stereo-matching cores (Ambrosch et al. 2008)."))
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name in COMMANDS if command is None else [command]:
        importlib.import_module(f"{__package__}.cmd_{name}").add_parser(subparsers)
    return parser


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    # The full parser (every command's module) only where its listing is needed: no
    # command, an unknown one, or --help before it.
    command = argv[0] if argv and argv[0] in COMMANDS else None
    try:
        args = build_parser(command).parse_args(argv)
        return args.run(args) or 0
    except UserError as error:
        print(f"npstereo: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("npstereo: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
