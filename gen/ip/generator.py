"""The FuseSoC generator: a user's core asks for a configuration by parameters.

``npstereo ip --fusesoc-generator --out DIR`` writes a generator core and a small script
into DIR (:func:`write_generator`). FuseSoC runs the script with the GAPI file of a
``generate:`` entry (its ``parameters`` and the ``vlnv`` the generated core must have) in
the folder the generated core goes to; the script calls :func:`main`, which turns the
parameters into the options of ``npstereo ip`` and runs it there. So a configuration made
by the generator is exactly the one the command line makes, with the same checks and the
same one-line errors.
"""

import sys
from pathlib import Path

import yaml

from ...params import UserError
from ..atomic import write_text
from ..cli.main import main as cli_main
from .fusesoc import generator_core_text

__all__ = ["GENERATOR_CORE", "GENERATOR_SCRIPT", "PARAMETERS", "gapi_arguments",
           "write_generator", "main"]

GENERATOR_CORE = "npstereo_generator.core"
GENERATOR_SCRIPT = "npstereo_fusesoc_generator.py"
GENERATOR_VLNV = "npstereo:stereo:generator:0"

#: The parameters a ``generate:`` entry may give, as ``npstereo ip`` spells them; the
#: flags ``--no-lr-check`` and ``--no-p2-adapt`` are given as ``lr_threshold: off`` and
#: ``p2_adapt: off``.
PARAMETERS = ("transform", "block", "disparities", "rounds", "aggregation", "lr_threshold",
              "line_buffer", "lut_inputs", "width", "height", "p1", "p2", "p2_adapt",
              "subpixel_bits")
_OFF = {"lr_threshold": "--no-lr-check", "p2_adapt": "--no-p2-adapt"}

_SCRIPT = '''\
"""FuseSoC generator of npstereo cores, written by `npstereo ip --fusesoc-generator`.

FuseSoC runs it as `INTERPRETER {script} GAPI-FILE` (see {core})."""
import sys

from npstereo.gen.ip.generator import main

sys.exit(main(sys.argv[1:]))
'''


def gapi_arguments(gapi):
    """The ``npstereo ip`` options of a GAPI document (a dict), without ``--out``."""
    parameters = gapi.get("parameters") or {}
    if not isinstance(parameters, dict):
        raise UserError("generator parameters must be a mapping of names to values")
    unknown = sorted(set(parameters) - set(PARAMETERS))
    if unknown:
        raise UserError(f"unknown generator parameter {unknown[0]}: allowed are "
                        f"{', '.join(PARAMETERS)}")
    argv = ["--vlnv", str(gapi.get("vlnv", ""))]
    for name in PARAMETERS:
        if name not in parameters:
            continue
        value = parameters[name]
        # YAML reads a bare off as False.
        if name in _OFF and (value is False or value == "off"):
            argv.append(_OFF[name])
        elif isinstance(value, (int, str)) and not isinstance(value, bool):
            argv += [f"--{name.replace('_', '-')}", str(value)]
        else:
            raise UserError(f"generator parameter {name} must be a number or a word, not "
                            f"{value!r}")
    return argv


def main(argv):
    """Run the generator on the GAPI file ``argv[0]``, writing into the current folder;
    the exit code of ``npstereo ip`` (2 with one line on stderr for bad parameters)."""
    try:
        if len(argv) != 1:
            raise UserError("usage: npstereo_fusesoc_generator.py GAPI-FILE")
        try:
            gapi = yaml.safe_load(Path(argv[0]).read_text())
        except (OSError, yaml.YAMLError) as error:
            raise UserError(f"cannot read the GAPI file {argv[0]}: {error}") from None
        if not isinstance(gapi, dict):
            raise UserError(f"the GAPI file {argv[0]} is not a mapping")
        options = gapi_arguments(gapi)
    except UserError as error:
        print(f"npstereo: error: {error}", file=sys.stderr)
        return 2
    return cli_main(["ip", "--out", ".", *options])


def write_generator(out):
    """Write the generator core and its script into the folder ``out``; the paths."""
    core, script = out / GENERATOR_CORE, out / GENERATOR_SCRIPT
    write_text(script, _SCRIPT.format(script=GENERATOR_SCRIPT, core=GENERATOR_CORE))
    # The interpreter that runs npstereo now: FuseSoC may run in another environment.
    write_text(core, generator_core_text(GENERATOR_VLNV, sys.executable, GENERATOR_SCRIPT))
    return [core, script]
