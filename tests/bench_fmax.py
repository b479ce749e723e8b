"""Benchmark of the clock: census 7x7 at the paper's size placed and routed on an ECP5-85k.

Synthesises (native Yosys) and places and routes (nextpnr-ecp5 --85k, router2) the paper's
census 7x7 core at 450 x 375, D = 100, R = 10, L/R check on, uncached, and prints the Fmax,
the frames/s it gives, the logic depth in LUT levels after mapping, the critical path and
the wall time. Issue 9's bar is 150 MHz. ``--dataset`` is accepted for ``make bench`` and
unused: synthesis needs no images. Takes several minutes (place and route is
single-threaded).
"""

import argparse
import time

from npstereo.gen.reports.synthesis import synthesis_report
from npstereo.params import TRANSFORMS, StereoParams


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", help="unused (synthesis needs no images)")
    parser.add_argument("--transform", choices=TRANSFORMS, default="census")
    parser.add_argument("--block", type=int, default=7)
    parser.add_argument("--freq", type=float, default=150.0,
                        help="nextpnr's target clock in MHz (default 150)")
    args = parser.parse_args()
    params = StereoParams(transform=args.transform, block=args.block, disparities=100,
                          rounds=10, width=450, height=375)
    started = time.perf_counter()
    report = synthesis_report(params, ["ecp5"], pnr=True, freq=args.freq)
    result = report["results"]["ecp5"]
    name = f"{params.transform} {params.block}x{params.block} D=100 R=10 450x375"
    if result["status"] != "ok":
        raise SystemExit(f"{name}: {result['status']}: {result['message']}")
    print(f"{name} on ECP5-85k: Fmax {result['fmax_mhz']:.1f} MHz, "
          f"{result['frames_per_second']:.1f} frames/s "
          f"({report['cycles_per_frame']:,} cycles per frame), "
          f"{result['logic_levels']:.1f} LUT levels, {result['logic']:,} LUT4 "
          f"({result['utilisation']['LUT']} %), {result['registers']:,} FF, "
          f"{result['block_rams']} DP16KD; {time.perf_counter() - started:.0f} s")
    print(f"critical path: {result['critical_path']}")


if __name__ == "__main__":
    main()
