"""``npstereo ip``: one core as a package for FuseSoC, IP-XACT catalogues and Platform
Designer (:mod:`npstereo.gen.ip`), or the FuseSoC generator that makes such packages."""

import sys

from ...hdl.plan import MAX_BLOCK, MAX_DISPARITIES, MAX_WIDTH, check_buildable
from ...params import UserError
from ..ip.generator import write_generator
from ..ip.package import default_vlnv, parse_vlnv, write_package
from .arguments import add_hardware_arguments, add_matching_arguments, check_output_folder, \
    params_from_args

__all__ = ["DESCRIPTION", "add_arguments", "run"]

DESCRIPTION = ("Write one stereo core as a package into a folder: its Verilog, a FuseSoC "
               "CAPI2 core (targets default, lint, sim), an IP-XACT 1685-2014 component "
               "(component.xml) and a Platform Designer component (_hw.tcl). With "
               "--fusesoc-generator, write instead the FuseSoC generator core that makes "
               "such packages from parameters.")


def run(args):
    out = check_output_folder(args.out)
    if args.fusesoc_generator:
        given = [name for name, value in (("--width", args.width), ("--height", args.height))
                 if value is not None]
        if given:
            raise UserError(f"--fusesoc-generator writes no core: {' and '.join(given)} "
                            "belong to the generate: entry of a core")
        for path in write_generator(out):
            print(path)
        return
    missing = [name for name, value in (("--width", args.width), ("--height", args.height))
               if value is None]
    if missing:
        raise UserError(f"{' and '.join(missing)} required: the image size of the core")
    vlnv = parse_vlnv(args.vlnv)
    # Validated before any elaboration: a bad configuration writes nothing.
    params = params_from_args(args).with_size(args.width, args.height)
    check_buildable(params)
    print(f"generating {params.describe()} and its test frame ...", file=sys.stderr,
          flush=True)
    for path in write_package(out, params, vlnv):
        print(path)


def add_arguments(parser):
    add_matching_arguments(parser, max_block=MAX_BLOCK, max_disparities=MAX_DISPARITIES, subpixel=True)
    add_hardware_arguments(parser)
    parser.add_argument("--width", type=int, help=f"image width W, at most {MAX_WIDTH}")
    parser.add_argument("--height", type=int, help="image height H")
    parser.add_argument("--vlnv", default=default_vlnv(),
                        help="name of the package in FuseSoC and IP-XACT, "
                             f"VENDOR:LIBRARY:NAME:VERSION (default {default_vlnv()})")
    parser.add_argument("--fusesoc-generator", action="store_true",
                        help="write the FuseSoC generator core (npstereo_generator.core and "
                             "its script) instead of a core")
    parser.add_argument("--out", required=True, help="folder to write the package into")
    parser.set_defaults(run=run)
