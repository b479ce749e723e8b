"""A lower bound on the logic of an exact ext. census core whose memory is at most the
paper's (issue 10), at the paper's sizes, and an estimate of a schedule outside it: prints
the two tables of docs/resources.md "Ext. census memory".

    .venv/bin/python docs/resources/ext_census_bound.py        # several minutes

The box sum of row y needs the costs of rows y - 1, y and y + 1 at every (column,
disparity). A cost of an earlier row is either kept (at least cost_bits - 1 bits per
(column, disparity): its parity is the only part that is free to compute again, from the
pixels' low bits) or computed again (a sum of k absolute differences). The right
transforms of the rows a unit computes are kept (R words of 8 k bits per unit and row)
or computed again (k absolute differences per unit and row). With the memory at most the
paper's, and nothing else in the memory but the B - 1 rows of pixels every window needs,
this finds the fewest sums of differences per clock, and counts their logic at what one
sum costs in this flow (Yosys ``synth_intel_alm``, the flow the bar is measured with; the
cheapest of the cost units' sum arranged for 4- and for 6-input LUTs, a third leaf form and
two register spacings, synthesised here). Everything
else in a core (transforms, aggregation, minimum trees, control) counts as nothing, so the
real core is larger still.

The floor column needs no synthesis: 8 ALUTs per 8-bit difference (one per result bit)
and half an ALUT per bit a three-input adder tree removes, per sum and per transform.

A second table estimates a core outside that bound, not built: a strip of n rows worked in
tiles of T columns, row by row within a tile (docs/resources.md, "Outside the bound").
Its sums per clock are D/R (n+2)(T+2)/(n T); its memory the pixel rows of the strip and of
the next one arriving, the right transforms of D + T + 1 columns twice (the row worked on
and the next), partial sums of two rows of the tile and n rows of results; the rest of the
core is counted as in the measured ``costs`` core with 6-input LUTs (its ALUTs in
docs/resources/sweep.json less its D/R sums), the schedule's own control as nothing.
"""

import json
from functools import cache
from pathlib import Path

from amaranth.back import verilog
from amaranth.hdl import Elaboratable, Module, Mux, Signal

from npstereo.gen.flow.capacity import DEVICES
from npstereo.gen.flow.synthesise import synthesise
from npstereo.gen.reports.paper_data import (PAPER_BLOCKS, PAPER_DISPARITIES, PAPER_LOGIC,
                                             PAPER_MEMORY, PAPER_ROUNDS, PAPER_SIZE)
from npstereo.hdl.trees import build_sad, build_sum, register_plan, sad_plan
from npstereo.params import LUT_INPUTS

W = PAPER_SIZE[0]
D, R, A = PAPER_DISPARITIES, PAPER_ROUNDS, 3
UNITS = D // R
#: The EP2S180's logic, the bar for every ext. census cell.
DEVICE_ALUTS = DEVICES["ep2s180"].capacity("ALUT")


class _Sum(Elaboratable):
    """sum |a_n - b_n| over k byte pairs between registers, as the cost units build it
    (``leaf_form`` their ``lut_inputs``), or as 2 sum max(a, b) - sum a - sum b."""

    def __init__(self, k, leaf_form, every):
        self.k, self.leaf_form, self.every = k, leaf_form, every
        self.a, self.b = Signal(8 * k), Signal(8 * k)
        self.en, self.sum = Signal(), Signal(20)

    def elaborate(self, platform):
        m = Module()
        a, b = Signal(8 * self.k), Signal(8 * self.k)
        m.d.sync += [a.eq(self.a), b.eq(self.b)]
        pairs = [(a.word_select(n, 8), b.word_select(n, 8)) for n in range(self.k)]
        if self.leaf_form in LUT_INPUTS:    # the cost units' own sum, either arrangement
            total = build_sad(m, self.en, pairs,
                              sad_plan(self.k, self.every, lut_inputs=self.leaf_form),
                              self.leaf_form)
        else:
            # 2 sum max(a, b) - sum a - sum b: the two sums are one per pixel, not counted.
            leaves = [Mux(x < y, y, x) for x, y in pairs]
            total = build_sum(m, self.en, leaves, register_plan(self.k, self.every, 1, False, 8))
        m.d.sync += self.sum.eq(total)
        return m


@cache
def sum_aluts(k):
    counts = []
    for form in (*LUT_INPUTS, "max"):
        for every in (2, 3):
            top = _Sum(k, form, every)
            text = verilog.convert(top, ports=[top.a, top.b, top.en, top.sum], name="top")
            counts.append(synthesise(text, "cyclonev", "top")["logic"])
    return min(counts)


def main():
    print("| block | memory budget | unit rows of costs kept | sums per clock | unit rows "
          "of right transforms computed again | bound (ALUT) | floor (ALUT) | bar (ALUT) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for i, block in enumerate(PAPER_BLOCKS):
        k = block * block - 1
        cost_bits = (255 * k).bit_length()
        budget = PAPER_MEMORY["ext-census"][i]
        free = budget - 2 * W * 8 * (block - 1)
        right_row = R * 8 * k                   # one unit's right words of one row
        cost_row = W * R * (cost_bits - 1)      # one unit's costs of one row
        free -= UNITS * A * right_row
        # Fractions count: a unit may keep the costs of some columns or rounds only.
        if free >= 0:
            kept, again = min(UNITS * (A - 1), free / (cost_row - right_row)), 0
        else:
            kept, again = 0, -free / right_row
        sums = UNITS * A - kept
        bound = sums * sum_aluts(k) + again * 8 * k
        floor = sums * (8 * k + (8 * k - cost_bits) / 2) + (again + 2 * A) * 8 * k
        paper = PAPER_LOGIC["ext-census"][i]
        bar = DEVICE_ALUTS if paper is None else min(DEVICE_ALUTS, int(0.7 * paper))
        print(f"| {block}x{block} | {budget:,} | {kept:.1f} | {sums:.1f} | {again:.1f} | "
              f"{bound:,.0f} | {floor:,.0f} | {bar:,} |", flush=True)


def costs_core_aluts(block):
    """Cyclone V ALUTs of the ext. census ``costs`` core with 6-input LUTs, from the
    committed sweep; None if it has no such figure."""
    sweep = json.loads((Path(__file__).parent / "sweep.json").read_text())
    for report in sweep["reports"]:
        p, result = report["params"], report["results"].get("cyclonev", {})
        if (p["transform"], p["block"], p.get("line_buffer"), p.get("lut_inputs")) == (
                "ext-census", block, "costs", 6) and result.get("status") == "ok":
            return result["logic"]
    return None


def strip_estimate():
    print("\n| block | n rows | T columns | sums per clock | memory bits | budget | "
          "estimate (ALUT) | bar (ALUT) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for i, block in enumerate(PAPER_BLOCKS):
        k = block * block - 1
        core = costs_core_aluts(block)
        if core is None:
            continue
        other = core - UNITS * sum_aluts(k)
        summed_bits = (A * A * 255 * k).bit_length()
        budget = PAPER_MEMORY["ext-census"][i]
        best = None
        for n in range(1, 64):
            for T in range(1, 256):
                memory = (2 * (2 * n + block + 1) * W * 8 + 2 * (D + T + 1) * 8 * k
                          + 2 * (T + 2) * D * summed_bits + n * W * 7)
                if memory > budget:
                    continue
                sums = UNITS * (n + 2) * (T + 2) / (n * T)
                if best is None or sums < best[0]:
                    best = (sums, n, T, memory)
        paper = PAPER_LOGIC["ext-census"][i]
        bar = DEVICE_ALUTS if paper is None else min(DEVICE_ALUTS, int(0.7 * paper))
        if best is None:
            print(f"| {block}x{block} | - | - | - | - | {budget:,} | no fit | {bar:,} |")
            continue
        sums, n, T, memory = best
        print(f"| {block}x{block} | {n} | {T} | {sums:.1f} | {memory:,} | {budget:,} | "
              f"{sums * sum_aluts(k) + other:,.0f} | {bar:,} |", flush=True)


if __name__ == "__main__":
    main()
    strip_estimate()
