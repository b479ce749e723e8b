"""The ``npstereo`` command: one subcommand per module ``cmd_<name>`` of this package.

A command module exposes ``DESCRIPTION``, ``add_arguments(parser)`` and ``run(args)``.
Only the module of the command being run is imported, by name (the one dynamic import of
the project, ``tests/test_structure.py``): the commands pull in very different libraries
(the golden model, Amaranth, cocotb, matplotlib, Dask), and neither ``npstereo --help``
nor ``npstereo match`` should wait for the ones they do not use. The listing of
``npstereo --help`` comes from :data:`COMMANDS` alone.

Every expected failure (bad parameter, unreadable file, unwritable output) is raised as a
:class:`~npstereo.params.UserError` and printed here as one line, exit code 2, no
traceback.
"""

import argparse
import importlib
import sys

from ...params import UserError

__all__ = ["main", "UsageError", "build_parser", "COMMANDS"]

#: Every command and its one-line help, in the order ``npstereo --help`` lists them.
COMMANDS = {
    "match": "disparity map of one stereo pair (golden model)",
    "eval": "correct matches (%%) against ground truth for one or many configurations",
    "paper": "regenerate the paper's quality figures (Figs. 6, 8, 10-12)",
    "demo": "run everything on the embedded synthetic scene",
    "verilog": "generate the Verilog of a stereo core",
    "ip": "package a core for FuseSoC, IP-XACT and Platform Designer",
    "cosim": "co-simulate the generated core on one frame, bit for bit",
    "prove": "prove the core's AXI4-Stream properties (SymbiYosys)",
    "report": "FPGA resources and clock of a core (Yosys, nextpnr)",
    "explore": "quality x logic x memory x clock of a grid for one device (Dask)",
    "board": "a bitstream that shows the disparity map on a board's HDMI port",
}


class UsageError(UserError):
    """A malformed command line."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(f"{self.prog}: {message}")


def build_parser(command=None):
    """The parser of every command, with the options of ``command`` (which then must be
    given); the others are listed with their help only."""
    parser = _Parser(prog="npstereo", description=(
        "Generate and verify FPGA stereo-matching cores (Ambrosch et al. 2008)."))
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name, summary in COMMANDS.items():
        if name != command:
            subparsers.add_parser(name, help=summary)
            continue
        module = importlib.import_module(f"{__package__}.cmd_{name}")
        module.add_arguments(subparsers.add_parser(name, help=summary,
                                                   description=module.DESCRIPTION))
    return parser


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
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
