"""Semi-global aggregation in hardware: four raster-order paths, summed, bit-exact.

Hardware counterpart of :mod:`npstereo.golden.sgm` (docs/sgm.md is the contract) and the
aggregation choice beside :mod:`.aggregation`'s A x A box, with its interface: the round's
D/R costs in, the round's D/R summed costs out, slot-aligned after a fixed latency; plus
the left gray pixels adaptive P2 compares. The costs arrive as Cmax where x - d < 0 (the
calculation stage masks them so for SGM), and S(x, d) = L_left + L_top-left + L_top +
L_top-right leaves for the same WTA, right-referenced WTA and L/R check as the box sums.

Round j carries d = j*D/R + i on lane i (the contiguous partitions of the calculation
stage): the neighbours d - 1 and d + 1 of a lane are its neighbouring lanes, except across
the round's edges, where they are the last lane of round j - 1 and the first lane of round
j + 1, one clock before and after in every stream below.

**Paths from the row above** (top-left, top, top-right). Their predecessor lies in the
previous row, finished long ago. Each keeps that row's L in block RAM, one word of D/R
values per (column, round): top and top-left in one memory read at the position's own
column x, top-right in another read at column x + 1 (both written at column x). Top-left
needs column x - 1, which position x - 1 of this row has already overwritten: it takes the
word position x - 1 read for its own column, held for one position in a store of R words
(LUT RAM). The previous row's minima m (one word of the three per column) are read at
column x + 1 and handed on by registers: top-right uses the word at once, top a position
later, top-left two positions later. Then, per lane, L = C + min(Lq(d), Lq(d +- 1) + P1,
m + P2) - m, in the normalised form C + min(min(Lq(d), Lq(d +- 1) + P1) - m, P2).

**The left path** (:mod:`.sgm_left`): its large step takes the tracked reference of
docs/semantics.md ("The left path"), so its loop is a lane update of one or two clocks at
any R, and its output is normalised by the exact m(x - 1) outside the loop.

**Fresh starts and stale state.** A path whose predecessor is outside the image starts
fresh, L = C, decided from the tag: the left path at x = 0, top-left at x = 0 or y = 0, top
at y = 0, top-right at y = 0 or x = W - 1. Its inputs from memory are then not used at all,
so what a memory held before (another frame, rows above the frame, a reset, power-up)
never reaches a result of the frame; memories and stores are written only in slots that
carry a position.
"""

from amaranth.hdl import Cat, Const, Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from ..params import P2_ADAPT_OFF, SGM_PATH_STEPS, SGM_PATHS, SGM_ROW_PATHS
from .banks import banked_memory, line_memory
from .common import LaneStores, SlotClock, bits_for, delay_line, \
    register, replica, split_lanes, tag_layout, taps
from .plan_structure import row_banks
from .plan_timing import SGM_ABOVE_EVERY, SGM_ROW_CLOCKS, sgm_delays, sgm_fifth_timing, \
    sgm_timing
from .sgm_left import PathOwner, left_path
from .sgm_right import fifth_path
from .trees import DEFAULT_EVERY, build_sum, build_tree, register_plan

__all__ = ["GUIDE", "guide_pixels", "SemiGlobalAggregation"]

#: Where the previous row's minima word is registered, after the input: the column copied
#: at 1, the address at 2, the read at 3 (:meth:`SemiGlobalAggregation._row_minima`).
_MINIMA_WORD = 4

#: The left window's pixels adaptive P2 compares, as (dy, dx) from the centre: the pixel
#: itself, then each path's predecessor in ``params.SGM_PATHS`` order.
GUIDE = ((0, 0),) + tuple((dy, dx) for dx, dy in SGM_PATH_STEPS.values())


def guide_pixels(window, block):
    """The :data:`GUIDE` pixels of a B x B window (row-major), packed low to high."""
    r = (block - 1) // 2
    return Cat(*(window[(dy + r) * block + dx + r] for dy, dx in GUIDE))


def _fresh(path, x, y, width):
    """The path starts fresh at (x, y): its predecessor lies outside the image."""
    first_column, last_column, first_row = x == 0, x == width - 1, y == 0
    return {"left": first_column, "top-left": first_column | first_row,
            "top": first_row, "top-right": first_row | last_column}[path]


def _adaptive_p2(step, p1, p2, adapt):
    """P2_r(p) = max(P1, P2 >> s) with s = max(0, bitlen(g) - t) for the step g (8 bits).

    s >= k exactly when g >= 2^(t + k - 1), i.e. when a bit of g from t + k - 1 up is set:
    one OR per k and a chain of multiplexers between constants (the largest k wins), no
    priority encoder and no shifter.
    """
    bits = bits_for(p2)
    value = Const(p2, bits)
    for shift in range(1, 9 - adapt):
        value = Mux(step[adapt + shift - 1:].any(), Const(max(p1, p2 >> shift), bits), value)
    return value


def _smaller(lower, upper):
    """min of two items of a minimum tree (values only)."""
    return (Mux(upper[0] < lower[0], upper[0], lower[0]),)


def _minimum3(centre, lower, upper):
    """Which of (centre, lower, upper) is the smallest, as the selects (lower wins, upper
    wins): the three comparisons side by side, instead of two one behind the other."""
    lower_wins = (lower < centre) & ~(upper < lower)
    upper_wins = (upper < centre) & (upper < lower)
    return lower_wins, upper_wins


def _chosen3(selects, centre, lower, upper):
    """The value :func:`_minimum3`'s ``selects`` choose."""
    lower_wins, upper_wins = selects
    return Mux(lower_wins, lower, Mux(upper_wins, upper, centre))


def _normalised(below, over, p2, fresh):
    """A path from above: min(best - m, P2) for best = min(Lq(d), Lq(d +- 1) + P1) >= m,
    from ``below`` = (best <= m + P2) and ``over`` = best - m (valid when ``below``); 0 at a
    fresh start (L = C)."""
    return Mux(fresh, 0, Mux(below, over, p2))


class SemiGlobalAggregation(PathOwner, wiring.Component):
    """Summed path costs S of the round's D/R disparities, for the position of the tag.

    Parameters
    ----------
    params : StereoParams
        With ``aggregation="sgm"``, width and height (any R that divides D;
        :func:`npstereo.hdl.plan.check_buildable`).
    every : int
        Register spacing of the adder of the four paths (see :mod:`.trees`); everything
        else is registered where :func:`~.plan_timing.sgm_timing` puts it.

    Attributes
    ----------
    costs : In(ArrayLayout(unsigned(cost_bits), D/R))
        C(x, j*D/R + i) on lane i in round j; Cmax where x - d < 0.
    guide : In(ArrayLayout(unsigned(8), 5))
        The left gray pixels of :data:`GUIDE` around the position (slot-aligned), for
        adaptive P2 (unused with a constant P2).
    tag : In(tag_layout)
        The position, slot-aligned at the input.
    first, round : In
        Slot timing at the input.
    sums : Out(ArrayLayout(unsigned(aggregated_cost_bits), D/R))
        S(x, j*D/R + i) on lane i.
    centre : Out(tag_layout)
        The position of ``sums`` (the input tag, delayed).
    latency : int
        Clocks from the input to the output.
    from_costs : bool
        False: SGM keeps no matching costs of the rows above (see :mod:`.aggregation`).
    """

    from_costs = False

    def __init__(self, params, every=DEFAULT_EVERY, slot_base=0):
        self.params, self.every, self.slot_base = params, every, slot_base
        self.timing = sgm_timing(params, every)
        self.latency = (sgm_fifth_timing(params, every) if params.fifth_path
                        else self.timing).latency
        units = params.per_round
        super().__init__({
            "costs": In(data.ArrayLayout(unsigned(params.cost_bits), units)),
            "guide": In(data.ArrayLayout(unsigned(8), len(GUIDE))),
            "tag": In(tag_layout(params)),
            "first": In(1), "round": In(bits_for(params.rounds - 1)),
            "sums": Out(data.ArrayLayout(unsigned(params.aggregated_cost_bits), units)),
            "centre": Out(tag_layout(params)),
        })

    def elaborate(self, platform):
        p, t = self.params, self.timing
        m = Module()
        self._slots = slots = SlotClock(m, self.first, self.round, p.rounds, "sgm",
                                        self.slot_base)
        self._valid = {}
        units = p.per_round
        costs = Cat(*(self.costs[i] for i in range(units)))
        #: The round's costs C, k clocks late at index k.
        self._costs = [split_lanes(word, units, p.cost_bits) for word in
                       taps(m, costs, max(t.rows - 1, t.loop + t.left_stages - 1,
                                           t.left_picks[-2] + 1,
                                           sgm_fifth_timing(p, self.every).costs + 1
                                           if p.fifth_path else 0), "sgm_cost")]
        # Fresh starts of the position, slot-aligned with P2 (two registers after the tag).
        fresh = {}
        for path in SGM_PATHS:
            name = f"sgm_fresh_{path.replace('-', '_')}"
            flag = register(m, _fresh(path, self.tag.x, self.tag.y, p.width), 1, name)
            fresh[path] = taps(m, flag, t.guide - 1, name)[-1]
        p2 = self._penalties(m)
        left = left_path(self, m, fresh["left"], p2["left"])
        rows = self._row_paths(m, fresh, p2)
        # The three L from above are summed as soon as they are there, and their sum waits
        # for the left path's L (at R = 1 fourteen clocks): one sum of 9 bits a lane in the
        # delay line instead of three L of 7 (5,600 of the 55,700 flip-flops of census 5x5
        # at D = 64, R = 1, before the delay lines were LUT RAM).
        plan = register_plan(len(SGM_ROW_PATHS), SGM_ABOVE_EVERY, 0, True)
        above = [build_sum(m, 1, [rows[path][i] for path in SGM_ROW_PATHS], plan)
                 for i in range(units)]
        delays = sgm_delays(p, self.every)
        above_bits = len(above[0])
        assert above_bits == p.path_cost_bits + 2, "plan_memories counts its delay line so"
        above = split_lanes(delay_line(m, Cat(*above), delays["above"], "sgm_above_aligned"),
                            units, above_bits)
        left = split_lanes(delay_line(m, Cat(*left), delays["left"], "sgm_left_aligned"),
                           units, p.left_cost_bits)
        plan = register_plan(2, self.every, 0, True)
        totals = [build_sum(m, 1, [left[i], above[i]], plan) for i in range(units)]
        if p.fifth_path:
            totals, (x, y, valid, live) = fifth_path(self, m, totals, p2["left"])
            m.d.comb += [self.centre.x.eq(x), self.centre.y.eq(y),
                         self.centre.valid.eq(valid), self.centre.live.eq(live)]
        else:
            m.d.comb += self.centre.eq(slots.delay(self.tag, 0, self.latency, "sgm_centre"))
        for i, total in enumerate(totals):
            m.d.comb += self.sums[i].eq(total[:p.aggregated_cost_bits])
        return m

    def _penalties(self, m):
        """P2 of each path at the position, slot-aligned at ``timing.guide`` (constants
        with a constant P2)."""
        p = self.params
        if p.p2_adapt == P2_ADAPT_OFF:
            return {path: Const(p.p2, bits_for(p.p2)) for path in SGM_PATHS}
        centre = self.guide[0]
        result = {}
        for k, path in enumerate(SGM_PATHS, 1):
            name = path.replace("-", "_")
            # The difference, then its magnitude: in one clock they were census 7x7 SGM's
            # critical path at R = 10 (6.73 ns, 6 levels, 148.7 MHz).
            difference = register(m, centre - self.guide[k], signed(9),
                                  f"sgm_difference_{name}")
            step = register(m, Mux(difference < 0, -difference, difference)[:8], 8,
                            f"sgm_step_{name}")
            result[path] = register(m, _adaptive_p2(step, p.p1, p.p2, p.p2_adapt),
                                     bits_for(p.p2), f"sgm_p2_{name}")
        return result

    def _running_min(self, m, values, offset, name):
        """The minimum over a slot's rounds of the minimum over ``values`` (round j's at
        ``offset`` + j): a tree of T registers, then a running minimum that restarts in
        round 0; complete in the clock ``offset`` + T + R."""
        slots = self._slots
        tree = build_tree(m, 1, [(v,) for v in values], _smaller,
                          register_plan(len(values), 1))[0]
        at = offset + self.timing.tree
        running = Signal(tree.shape(), name=name, reset_less=True)
        m.d.sync += running.eq(Mux(slots.first(at) | (tree < running), tree, running))
        return running

    def _row_paths(self, m, fresh, p2):
        """L of top-left, top and top-right per lane, at ``timing.rows``.

        Offsets after the input, for round j, with the rows in one bank (a clock later per
        level of the bank's choice with several, ``plan_timing.sgm_row_clocks``): the row
        bases at 2, the word addresses at 3 + j, the words out of the block RAMs' output
        registers at 5 + j, the top-left word held from the previous position beside them
        at 6 + j; the first lane of round j + 1 arrives a clock later, so the candidates
        L + P1 are formed at 8 + j, their comparisons at 9 + j, their minimum at 10 + j, its
        comparison with m + P2 and difference to m at 11 + j, the normalised step at
        12 + j, and L = C + the step at 13 + j, which goes into the minima and, from
        registers of its own, back to the position's own column at 14 + j.
        """
        p, t, slots = self.params, self.timing, self._slots
        units, rounds, width = p.per_round, p.rounds, p.width
        bits, p1 = p.path_cost_bits, p.p1
        plus_bits = (p.max_cost + p.p2 + p1).bit_length()
        ones = (1 << plus_bits) - 1
        word_bits = units * bits
        x = self.tag.x

        # Row addresses (x * R and, for top-right, (x + 1) * R), slot-aligned at 2, without a
        # multiplier: consecutive positions are raster-continuous (x + 1, or 0 at a line
        # start), so the bases advance by R per position. The column's flags are registered
        # first: the input's column through its comparisons and the choice into the bases
        # was census 5x5 SGM's critical path at 1280 x 720, D = 64, R = 4 (10.9 ns).
        depth = width * rounds
        # Kept as registers of their own: synthesis merged the first column's with the left
        # path's fresh flag (the same x == 0, registered), whose loads lie across the
        # core (census 5x5 SGM at 1280 x 720, R = 4: 6.70 ns into the next row base, 5.28
        # of it wire, at two seeds).
        first_column = replica(m, x == 0, "sgm_row_first_column", reset_less=True)
        last_column = replica(m, x == width - 1, "sgm_row_last_column", reset_less=True)
        own = Signal(range(depth), name="sgm_row_base", reset_less=True)
        nxt = Signal(range(depth), name="sgm_row_base_next", reset_less=True)
        # They step in round 0 of a slot with a position, decided a clock ahead into a
        # register of their own: the slot's valid tap into both bases' enables was census
        # 7x7 SGM's path at R = 10 (6.64-7.27 ns) and census 5x5's at 1280 x 720, R = 4.
        step = replica(m, slots.first(0) & self._valid_at(0), "sgm_row_base_step")
        # The next column's base needs no restart at a first column (after a reset in
        # mid-row): only the top-right reads use it, which are fresh in row 0, and row 0
        # ends at its last column. The restart into it was census 5x5 SGM's path at
        # 1280 x 720, R = 4 again (6.74 ns, 2 levels).
        with m.If(step):
            m.d.sync += [own.eq(Mux(first_column, 0, own + rounds)),
                         nxt.eq(Mux(last_column, 0, nxt + rounds))]
        # The address at 3, the read at 4, the RAM's output register at 5, then the levels
        # of the bank's choice: the word at 5 + t.rows - SGM_ROW_CLOCKS.
        word_at = 5 + t.rows - SGM_ROW_CLOCKS
        normalise = word_at + 5     # newest word, + P1, comparisons, minimum of three
        assert t.rows == normalise + 3, "plan_timing.SGM_ROW_CLOCKS counts the same steps"
        banks = row_banks(p)
        # L back into the rows' memories at the position's own column, at t.rows.
        # A counter of its own, loaded with the base in round 0 (the base + the shared round
        # counter was census 7x7 SGM's critical path at R = 10: that counter's 7.7 ns of
        # routing into the adder), a clock ahead, then copied for each few block RAMs
        # (banked_memory): the counter driving all 61 block RAMs' write addresses was the
        # next (9.77 ns).
        # L is written a clock after t.rows, from registers of its own: L's registers into
        # the block RAMs' data, beside the minimum trees and the sum, were census 7x7 SGM's
        # path at R = 10 (the trees' first level, 6.72-7.16 ns, in two placements of four).
        write_count = Signal(range(depth), name="sgm_rows_write_count", reset_less=True)
        m.d.sync += write_count.eq(Mux(
            slots.first(t.rows - 1),
            self._aligned(own, 2, t.rows - 1, "sgm_rows_base"), write_count + 1))
        written = {"top": Signal(2 * word_bits, name="sgm_rows_top_written", reset_less=True),
                   "top_right": Signal(word_bits, name="sgm_rows_top_right_written",
                                       reset_less=True)}
        words = []
        for name, base in (("top", own), ("top_right", nxt)):
            address = Signal(range(depth), name=f"sgm_{name}_address_early")
            m.d.comb += address.eq(base + slots.round(2))
            words.append(banked_memory(m, f"sgm_rows_{name}", unsigned(len(written[name])),
                                       banks, address, write_count, written[name],
                                       self._valid_at(t.rows)))
        (top, top_left), top_right = split_lanes(words[0], 2, word_bits), words[1]
        # Top-left: the word the previous position read for its own column.
        # Copies of the round counter of its own for the write and, per few lanes, for the
        # read: the shared counter into the LUT RAM's read was census 7x7 SGM's path at
        # R = 10 (7.08 ns, 6.32 of it routing), one copy into all 16 lanes' read census 5x5
        # SGM's at 1280 x 720, R = 4 (8.48 ns, 7.72 wire).
        store = LaneStores(m, "sgm_top_left_store", units, bits, rounds)

        def round_copy(name):
            return slots.round(word_at) if rounds == 1 else \
                replica(m, slots.round(word_at - 1), name, reset_less=True)
        held = store.read(lambda k: round_copy(f"sgm_top_left_read_round{k}"))
        store.write(round_copy("sgm_top_left_write_round"), top_left, self._valid_at(word_at))
        newest = {"top-left": register(m, held, word_bits, "sgm_top_left_newest"),
                  "top": register(m, top, word_bits, "sgm_top_newest"),
                  "top-right": register(m, top_right, word_bits, "sgm_top_right_newest")}

        minima, minima_write = self._row_minima(m, p2, normalise)
        results, tree_leaves = {}, {}
        for path in SGM_ROW_PATHS:
            name = f"sgm_{path.replace('-', '_')}"
            word = split_lanes(newest[path], units, bits)                   # round j + 1 at 6 + j
            current = split_lanes(register(m, newest[path], word_bits, f"{name}_current"),
                                  units, bits)                              # round j at 6 + j
            plus = [register(m, v + p1, plus_bits, f"{name}_p{i}") for i, v in
                    enumerate(current)]                                # round j at 7 + j
            values = [register(m, v, bits, f"{name}_q{i}") for i, v in enumerate(current)]
            # The neighbours across the round's edges, for round j at 7 + j: the previous
            # round's last lane and the next round's first (none outside 0 .. D-1). The
            # edge flags registered from the round a clock earlier, per path: the shared
            # round counter through its comparisons into the three paths' multiplexers
            # was census 7x7 SGM's critical path at R = 10 (7.71 ns, 6.71 of it routing).
            round_ = slots.phased_round(word_at + 1, 0, f"{name}_round")
            first_round = register(m, round_ == 0, 1, f"{name}_first_round")
            last_round = register(m, round_ == rounds - 1, 1, f"{name}_last_round")
            before = register(m, Mux(first_round, ones, plus[units - 1]), plus_bits,
                              f"{name}_p_before")
            after = register(m, Mux(last_round, ones, word[0] + p1), plus_bits,
                             f"{name}_p_after")
            neighbours = [before, *plus, after]
            # The comparisons registered with their candidates, then the choice (both in
            # one clock were census 7x7 SGM's critical path at R = 10, 8.53 ns).
            best = []
            for i, v in enumerate(values):
                trio = [v, neighbours[i], neighbours[i + 2]]
                selects = register(m, Cat(*_minimum3(*trio)), 2, f"{name}_wins{i}")
                trio = [register(m, c, len(c), f"{name}_trio{i}_{k}") for k, c in
                        enumerate(trio)]
                best.append(register(m, _chosen3(selects, *trio)[:bits], bits,
                                     f"{name}_best{i}"))
            minimum, bound = minima[path]
            # The comparison with m + P2 and the difference to m side by side, then the
            # choice and + C (the three in one clock were 6 LUT levels, census 7x7).
            below = [register(m, b <= c, 1, f"{name}_below{i}")
                     for i, (b, c) in enumerate(zip(best, bound))]
            above_m = [register(m, (b - c)[:bits_for(p.p2)], bits_for(p.p2),
                                f"{name}_over{i}")
                       for i, (b, c) in enumerate(zip(best, minimum))]
            p2_now = self._lane_copies(m, p2[path], t.guide, normalise + 1, f"{name}_p2")
            fresh_now = self._lane_copies(m, fresh[path], t.guide, normalise + 1,
                                          f"{name}_fresh")
            # The choice registered, + C a clock later: both in one clock, behind P2's
            # register for every lane, were census 7x7 SGM's critical path at R = 10
            # (10.6 ns) once the comparisons above were registered.
            step = [register(m, _normalised(le, over, p2c, fc), bits_for(p.p2),
                             f"{name}_step{i}")
                    for i, (le, over, p2c, fc) in enumerate(zip(below, above_m, p2_now,
                                                               fresh_now))]
            sums = [c + s for c, s in zip(self._costs[t.rows - 1], step)]
            # L twice, both kept: one for the sum and the rows' write, a copy for the path's
            # minimum tree (one register into both was census 7x7 SGM's path at R = 10, into
            # the tree's first comparison, in four placements of eight: 6.70-7.16 ns).
            results[path] = [replica(m, v, f"{name}_l{i}", bits, reset_less=True)
                             for i, v in enumerate(sums)]
            tree_leaves[path] = [replica(m, v, f"{name}_l{i}_tree", bits, reset_less=True)
                                 for i, v in enumerate(sums)]

        m.d.sync += [written["top"].eq(Cat(*results["top"], *results["top-left"])),
                     written["top_right"].eq(Cat(*results["top-right"]))]
        # Their minima, once the last round's running minimum is complete.
        running = [self._running_min(m, tree_leaves[path], t.rows,
                                     f"sgm_{path.replace('-', '_')}_m") for path in SGM_ROW_PATHS]
        m.d.comb += [
            minima_write.write_addr.eq(self._aligned(x, 0, t.minima, "sgm_minima_column")),
            minima_write.write_data.eq(Cat(*running)),
            # Formed a clock ahead into a register of its own: the slot pulse's tap through
            # a LUT into the memory's enable was census 7x7 SGM's path at R = 10 (6.85 ns,
            # 450 x 375 on ECP5).
            minima_write.write_en.eq(replica(
                m, slots.first(t.minima - 1) & self._valid_at(t.minima - 1),
                "sgm_minima_write_en"))]
        return results

    def _row_minima(self, m, p2, offset):
        """Per path from above, m of its predecessor and m + P2, slot-aligned at ``offset``;
        and the minima memory (:func:`.banks.line_memory`; the caller writes it).

        One word of the three minima per column; position x reads column x + 1 (0 after
        the last column, whose value is then the current row's first), a word top-right
        uses at once, top a position later and top-left two positions later: registers
        shifted in every slot with a position.
        """
        p, t, slots = self.params, self.timing, self._slots
        bits = p.path_cost_bits
        # The column in a copy of its own first, the address a clock later: the tag into
        # the address's comparison and increment was census 7x7 SGM's path at R = 10
        # (6.78 ns, 450 x 375 on ECP5).
        x = replica(m, self.tag.x, "sgm_minima_tag_x", reset_less=True)
        memory = line_memory(m, "sgm_minima", 3 * bits, p.width)
        m.d.comb += memory.read_addr.eq(register(m, Mux(x == p.width - 1, 0, x + 1),
                                                  range(p.width), "sgm_minima_address"))
        word = dict(zip(SGM_ROW_PATHS, split_lanes(register(m, memory.read_data, 3 * bits,
                                                            "sgm_minima_word"), 3, bits)))
        # Column x + 1 for top-right now; for top as column x of the next position; for
        # top-left as column x - 1 two positions on.
        used = {path: Signal(bits, name=f"sgm_m_{path.replace('-', '_')}", reset_less=True)
                for path in SGM_ROW_PATHS}
        top_next = Signal(bits, name="sgm_m_top_next", reset_less=True)
        top_left_next = [Signal(bits, name=f"sgm_m_top_left_next{k}", reset_less=True)
                         for k in range(2)]
        with m.If(slots.first(_MINIMA_WORD) & self._valid_at(_MINIMA_WORD)):
            m.d.sync += [used["top-right"].eq(word["top-right"]),
                         used["top"].eq(top_next), top_next.eq(word["top"]),
                         used["top-left"].eq(top_left_next[1]),
                         top_left_next[1].eq(top_left_next[0]),
                         top_left_next[0].eq(word["top-left"])]
        result = {}
        for path in SGM_ROW_PATHS:
            name = f"sgm_{path.replace('-', '_')}"
            bound = register(m, used[path] + self._aligned(p2[path], t.guide,
                                                           _MINIMA_WORD + 1, f"{name}_p2m"),
                              bits + 1, f"{name}_bound")
            # Copied per group of lanes: one register of m + P2 into every lane's
            # comparison was census 7x7 SGM's path at R = 10 (7.40 ns, 5.26 of it routing).
            result[path] = (
                self._lane_copies(m, used[path], _MINIMA_WORD + 1, offset, f"{name}_m"),
                self._lane_copies(m, bound, _MINIMA_WORD + 2, offset, f"{name}_bound"))
        return result, memory
