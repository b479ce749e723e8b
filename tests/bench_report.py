"""Benchmark of the synthesis flow: how long Yosys (and nextpnr) take for one core.

Prints the figures and the wall time per target for a configuration (default: census 5x5,
D = 16, R = 4, 64 x 16), uncached. ``--dataset`` is accepted for ``make bench`` and unused:
synthesis needs no images.
"""

import argparse
import time

from npstereo.gen.flow.synthesise import synthesise
from npstereo.gen.flow.tools import TARGETS
from npstereo.hdl.plan_memories import memory_bits
from npstereo.hdl.plan_timing import cycles_per_frame
from npstereo.hdl.verilog import TOP_NAME, core_verilog
from npstereo.params import TRANSFORMS, StereoParams


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", help="unused (synthesis needs no images)")
    parser.add_argument("--transform", choices=TRANSFORMS, default="census")
    parser.add_argument("--block", type=int, default=5)
    parser.add_argument("--disparities", type=int, default=16)
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--width", type=int, default=64)
    parser.add_argument("--height", type=int, default=16)
    parser.add_argument("--pnr", action="store_true", help="also place and route for ECP5")
    args = parser.parse_args()
    params = StereoParams(transform=args.transform, block=args.block,
                          disparities=args.disparities, rounds=args.rounds,
                          width=args.width, height=args.height)
    started = time.perf_counter()
    verilog = core_verilog(params)
    print(f"{params.transform} {params.block}x{params.block} D={params.disparities} "
          f"R={params.rounds} {params.width}x{params.height}: Verilog generated in "
          f"{time.perf_counter() - started:.1f} s ({len(verilog.splitlines()):,} lines)")
    print(f"cycles per frame {cycles_per_frame(params):,}, memory bits expected "
          f"{memory_bits(params):,}")
    for target in TARGETS:
        result = synthesise(verilog, target, TOP_NAME, pnr=args.pnr)
        if result["status"] != "ok":
            print(f"{target}: {result['status']} {result['message']} ({result['seconds']} s)")
            continue
        fmax = "" if result["fmax_mhz"] is None else f", Fmax {result['fmax_mhz']:.1f} MHz"
        print(f"{target}: {result['logic']:,} {result['logic_unit']}, {result['registers']:,} "
              f"registers, {result['block_rams']} {result['block_ram_kind']}, "
              f"{result['memory_bits']:,} memory bits{fmax}: {result['seconds']:.1f} s")


if __name__ == "__main__":
    main()
