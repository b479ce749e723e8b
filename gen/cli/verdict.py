"""What the commands print of a co-simulation (``npstereo cosim``, ``npstereo demo``)."""

__all__ = ["print_verdict"]


def print_verdict(comparison, cycles, pixels, clock_mhz=100.0):
    """The co-simulation verdict: pixels compared, mismatches, cycles and frame rate."""
    fps = clock_mhz * 1e6 / cycles if cycles > 0 else 0.0
    verdict = "bit-exact" if comparison.ok else comparison.message()
    print(f"pixels compared:  {comparison.pixels}")
    print(f"mismatches:       {comparison.mismatches} ({verdict})")
    print(f"cycles per frame: {cycles} ({cycles / pixels:.2f} per pixel)")
    print(f"frame rate:       {fps:.1f} frames/s at {clock_mhz:g} MHz")
