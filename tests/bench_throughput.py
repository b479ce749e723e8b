"""Benchmark of throughput: census 5x5 SGM at 1280 x 720, D = 64, R = 1 on an ECP5-85k.

Synthesises (native Yosys) and places and routes (nextpnr-ecp5 --85k, router2) the core,
uncached, and prints its Fmax, frames/s and disparity evaluations per second (W H D fps, the
field's measure) beside the published peers, with the ratio to the best of them. Issue
27's bar: >= 150 MHz, >= 9.5 G evaluations/s. ``--dataset`` is accepted for ``make bench``
and unused. Place and route is single-threaded and takes tens of minutes at this size.
"""

import argparse
import time

from npstereo.gen.reports.camera import PEERS, evaluations_per_second as evaluations
from npstereo.gen.reports.synthesis import synthesis_report
from npstereo.params import SGM, StereoParams


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", help="unused (synthesis needs no images)")
    parser.add_argument("--block", type=int, default=5)
    parser.add_argument("--disparities", type=int, default=64)
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--height", type=int, default=720)
    parser.add_argument("--freq", type=float, default=150.0,
                        help="nextpnr's target clock in MHz (default 150)")
    args = parser.parse_args()
    params = StereoParams(transform="census", block=args.block, disparities=args.disparities,
                          rounds=args.rounds, aggregation=SGM, width=args.width,
                          height=args.height)
    started = time.perf_counter()
    report = synthesis_report(params, ["ecp5"], pnr=True, freq=args.freq)
    result = report["results"]["ecp5"]
    name = params.describe()
    if result["status"] != "ok":
        raise SystemExit(f"{name}: {result['status']}: {result['message']}")
    fps = result["frames_per_second"]
    ours = evaluations(params.width, params.height, params.disparities, fps)
    print(f"{name} on ECP5-85k: Fmax {result['fmax_mhz']:.1f} MHz, {fps:.1f} frames/s, "
          f"{ours / 1e9:.2f} G evaluations/s; {result['logic']:,} LUT4 "
          f"({result['utilisation']['LUT']} %), {result['registers']:,} FF, "
          f"{result['block_rams']} DP16KD, {result['logic_levels']:.1f} LUT levels; "
          f"{time.perf_counter() - started:.0f} s")
    print(f"critical path: {result['critical_path']}")
    print("| design | W x H | D | frames/s | G evaluations/s |\n|---|---|---:|---:|---:|")
    for peer, width, height, disparities, peer_fps in PEERS:
        print(f"| {peer} | {width}x{height} | {disparities} | {peer_fps:.0f} | "
              f"{evaluations(width, height, disparities, peer_fps) / 1e9:.1f} |")
    print(f"| npstereo SGM | {params.width}x{params.height} | {params.disparities} | "
          f"{fps:.0f} | {ours / 1e9:.2f} |")
    best = max(evaluations(*peer[1:]) for peer in PEERS)
    print(f"ratio to the best peer: {ours / best:.2f}")


if __name__ == "__main__":
    main()
