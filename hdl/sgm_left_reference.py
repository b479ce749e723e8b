"""The left path's reference of the large step in hardware: ref(x) + P2(x) from the files
that positions x - J .. x - 1 filled, and the picks that fill them.

Part of :func:`.sgm_left.left_path` (its module docstring, "The reference", describes
what these build; docs/hardware.md "Semi-global aggregation" the structure).
"""

from amaranth.hdl import Array, Cat, Const, Mux, Signal, unsigned

from ..params import SGM_TRACK_AGE, SGM_TRACK_STEPS
from .plan_timing import SGM_HISTORY_PAIRS_CLOCKS, SGM_LEFT_LATE_CLOCKS
from .common import bits_for, register, replica

__all__ = ["reference_sum", "pick_references"]


#: Bits of a file's entry chosen by one copy of its index: one register of the index into
#: all the bits' multiplexers was census 7x7 SGM's critical path at R = 10 (into a C(x - k,
#: b(x)) term, 6.72 ns, 3 levels; into the start Lu(x - J, b(x)), 6.85 ns, 5 levels).
BITS_PER_INDEX = 3


def _read_file(m, entries, index, name, split=False):
    """``entries[index]`` (``index`` a value a clock ahead, two with ``split``), the index
    registered once per :data:`BITS_PER_INDEX` bits of the entries; with ``split`` the
    multiplexer in two clocks (:func:`_pick`), so the entries are read a clock earlier."""
    width, parts = len(entries[0]), []
    for low in range(0, width, BITS_PER_INDEX):
        at = replica(m, index, f"{name}_{low}", unsigned(len(index)), reset_less=True)
        bits = [e[low:low + BITS_PER_INDEX] for e in entries]
        parts.append(_pick(m, bits, at, f"{name}_{low}") if split else Array(bits)[at])
    return Cat(*parts)


def _pick_groups(count, lane_bits):
    """The groups of :func:`_pick` over ``count`` values by a ``lane_bits``-bit lane."""
    return -(-count // (1 << (lane_bits + 1) // 2))


def _pick(m, values, lane, name, copies=None, registered=False):
    """values[lane] in two clocks: the lane's low bits select within groups (registered),
    the high bits the group (returned combinationally, a clock after ``values``; with
    ``registered`` into a register, two clocks after).
    ``copies``: the lane once per group (:func:`_pick_groups`), each group's select its
    own register."""
    width = len(values[0])
    if len(values) == 1:
        return register(m, values[0], width, f"{name}_g0")
    low = (len(lane) + 1) // 2
    size = 1 << low
    copies = copies or [lane] * _pick_groups(len(values), len(lane))
    groups = [register(m, Array(_padded(values[k:k + size], size))[copy[:low]], width,
                        f"{name}_g{k}")
              for copy, k in zip(copies, range(0, len(values), size))]
    high = register(m, lane[low:], max(1, len(lane) - low), f"{name}_high")
    if len(groups) == 1:
        chosen = groups[0]
    else:
        chosen = Array(_padded(groups, 1 << len(high)))[high]
    return register(m, chosen, width, f"{name}_chosen") if registered else chosen


#: Index bits of each level of :func:`_pick_by_pairs` (a 4:1 multiplexer).
_PAIR = 2


def _pick_by_pairs(m, values, lane, name, copies):
    """values[lane] through a registered level of 4:1 multiplexers per two bits of
    ``lane`` (2:1 for a last odd bit), low bits first, a clock each: the first level's
    groups each select by their own copy in ``copies`` (:func:`_pick_pair_groups`), the
    higher bits follow in registers of their own."""
    width, level = len(values[0]), 0
    selects, high = [copy[:_PAIR] for copy in copies], lane[_PAIR:]
    while True:
        size = 1 << len(selects[0])
        values = [register(m, Array(_padded(values[k:k + size], size))[select], width,
                           f"{name}_l{level}_{k}")
                  for select, k in zip(selects, range(0, len(values), size))]
        if len(values) == 1:
            return values[0]
        high = register(m, high, len(high), f"{name}_l{level}_high")
        level += 1
        select = high[:_PAIR]
        selects, high = [select] * -(-len(values) // (1 << len(select))), high[_PAIR:]


def _pick_pair_groups(count):
    """The first level's groups of :func:`_pick_by_pairs` over ``count`` values."""
    return -(-count // (1 << _PAIR))


def _padded(values, count):
    """``values`` repeated at their last up to ``count``: an index of log2(count) bits then
    covers every case (a partial case is a lint warning, and its default a latch-like
    hold in simulation), and the lanes past the last are never selected."""
    return list(values) + [values[-1]] * (count - len(values))


def reference_sum(owner, m, column, m0, p2, chosen, sums):
    """ref(x) + P2(x) in the clock ``loop`` - 1: the C(x - k, b(x)) that exist (x - k >= 1)
    read from their files and added to P2, then Lu(x - J, b(x)), or m(0) for x <= J
    (chosen a clock earlier into a register where ``timing.left_start_early``, Lu(x - J,
    b(x)) read into a register a clock before that where ``timing.left_start_read``).

    The sum: where ``timing.left_sum_late``, a clock per level of additions, C(x - 1,
    b(x)) (picked last) added to the others' sum in the last
    (:data:`~.plan_sgm_timing.SGM_LEFT_LATE_CLOCKS`); else all read
    ``timing.left_sum_clocks`` before, registered where that is two or three, the first
    level of additions registered where three."""
    t, steps = owner.timing, SGM_TRACK_STEPS
    bits, cost_bits = owner.params.left_loop_bits, owner.params.cost_bits
    index = steps.bit_length() - 1

    columns = {}

    def column_at(offset):      # one delay per offset, as in the netlists measured
        if offset not in columns:
            columns[offset] = column(offset)
        return columns[offset]

    def picked_cost(k, entries, at, split=False):
        """C(x - k, b(x)) or 0 (x - k < 1), from its file at ``at``. Which entry and
        whether it exists come from the column a clock ahead (a slot-aligned value holds
        for the slot's R clocks, so the registers hold this position's): the subtractions
        and comparisons in front of the files' multiplexers and the additions were census
        7x7 SGM's deepest path (7.1 LUT levels, ECP5); the files' multiplexers and the
        additions in one clock were its critical path at R = 10 (8.16 ns, 122.5 MHz).
        ``split``: the file read in two clocks (``timing.left_read_split``)."""
        x = column_at(at - 1)
        entry = column_at(at - 1 - split) - k
        return Mux(register(m, x > k, 1, f"sgm_left_has{k}"),
                   _read_file(m, entries, entry[:index], f"sgm_left_entry{k}", split), 0)

    def level(terms):       # a tree of additions, not a chain
        return [a + b for a, b in zip(terms[::2], terms[1::2])] + terms[len(terms) // 2 * 2:]

    def registered(terms, name):
        return [register(m, v, len(v), f"{name}{k}") for k, v in enumerate(terms)]

    if t.left_sum_late:
        late, rest = SGM_LEFT_LATE_CLOCKS
        at = t.left_reference - rest
        split = t.left_read_split
        terms = [register(m, picked_cost(k, entries, at, split), cost_bits,
                          f"sgm_left_term{k}")
                 for k, entries in enumerate(sums[1:], 2)]
        terms.append(owner._aligned(p2, t.guide, at + 1, "sgm_left_p2"))
        for depth in range(rest - 2):
            terms = registered(level(terms), f"sgm_left_level{depth}_")
        assert len(terms) == 1, "one level of additions per clock"
        first = register(m, picked_cost(1, sums[0], t.left_reference - late, split),
                         cost_bits, "sgm_left_term1")
        total = register(m, (terms[0] + first)[:bits], bits, "sgm_left_csum")
    else:
        at = t.left_reference - t.left_sum_clocks
        terms = [picked_cost(k, entries, at) for k, entries in enumerate(sums, 1)]
        if t.left_sum_clocks >= 2:
            terms = [register(m, term, cost_bits, f"sgm_left_term{k}")
                     for k, term in enumerate(terms, 1)]
        # With three clocks the first level of additions is registered (P2 joins it).
        first_level = t.left_sum_clocks == 3
        terms.append(owner._aligned(p2, t.guide, t.left_reference - 1 - first_level,
                                     "sgm_left_p2"))
        if first_level:
            terms = registered(level(terms), "sgm_left_pair")
        while len(terms) > 1:
            terms = level(terms)
        total = register(m, terms[0][:bits], bits, "sgm_left_csum")
    early, read = t.left_start_early, t.left_start_read
    x = column_at(t.left_reference - 1 - early)
    near = register(m, x <= steps, 1, "sgm_left_near")
    entry = _read_file(m, chosen, column_at(t.left_reference - 1 - early - read)[:index],
                       "sgm_left_chosen_at")
    if read:
        entry = register(m, entry, bits, "sgm_left_chosen")
    start = Mux(near, m0, entry)
    if early:
        start = register(m, start, bits, "sgm_left_start")
    return (start + total)[:bits]


def pick_references(owner, m, column, fresh_at, history, b0, lu, chosen, sums):
    """At position p, for k = 1 .. J: b(p + k) from the history (G(0) for p + k <= K), and
    C(p, b(p + k)) into ``sums[k - 1]`` (k < J) or Lu(p, b(p + J)) into ``chosen``, each
    at entry p mod J, in the round that holds b.

    b(p + k) for k >= ``timing.left_chain`` comes down a chain: position p reads b(p + J)
    and takes b(p + k) = b((p - 1) + (k + 1)) from the position before (shifted only in
    slots with a position, so gaps do not matter), then delays it to its pick; the k
    before the chain (at R = 1) read the history themselves."""
    p, t, slots = owner.params, owner.timing, owner._slots
    steps = SGM_TRACK_STEPS
    lane_bits = bits_for(p.per_round - 1)
    index = steps.bit_length() - 1
    tracked = {k: _history_read(owner, m, column, history, b0, k, at)
               for k, at in enumerate(t.left_picks[:t.left_chain - 1], 1)}
    shift_at = t.left_chain_at
    shift = _chain_shift(owner, shift_at)
    link = _history_read(owner, m, column, history, b0, steps, shift_at, shift,
                         t.left_chain_history)
    for k in range(steps, t.left_chain - 1, -1):
        if k < steps:
            link = register(m, Mux(_young(m, column, k, shift_at, t.left_history), b0, link),
                            len(b0), f"sgm_left_chain{k}", shift)
        tracked[k] = slots.delay(link, shift_at + 1, t.left_picks[k - 1] - shift_at,
                                 f"sgm_left_b{k}", reset_less=True)
    for k, at in enumerate(t.left_picks, 1):
        b = tracked[k]
        lane, round_ = b[:lane_bits], b[lane_bits:]
        if k < steps:
            values, files, picked_at = owner._costs[at + 1], sums[k - 1], at + 2
        else:
            values, files, picked_at = lu, chosen, t.left_lu + 1
        picked = _pick(m, values, lane, f"sgm_left_pick{k}")
        # b holds for R clocks only: its round is compared beside the first pick level.
        match = register(m, slots.round(picked_at - 1) == round_, 1, f"sgm_left_match{k}")
        # Which entry is written, decoded a clock ahead into a flag per entry: the shared
        # valid flag through the decoder into a file's enables was census 7x7 SGM's path
        # at R = 10 (7.21 ns, 6.21 of it routing).
        ahead = picked_at - 1
        write = owner._valid_at(ahead)
        if k == steps:
            write &= ~fresh_at(ahead)       # x <= J take m(0) instead
        here = column(ahead)[:index]
        for e, entry in enumerate(files):
            flag = Signal(name=f"sgm_left_write{k}_{e}")
            m.d.sync += flag.eq(write & (here == e))
            with m.If(flag & match):
                m.d.sync += entry.eq(picked)


def _chain_shift(owner, at):
    """The chain's shift: round 0 of a slot with a position at ``at``."""
    return owner._slots.first(at) & owner._valid_at(at)


def _young(m, column, k, at, ahead):
    """Whether position p + k <= K (b(p + k) = G(0)), from the column ``ahead`` clocks
    before ``at``, registered to it."""
    x = column(at - ahead)
    # (Always young where the column cannot pass K - k: a comparison with a constant
    # beyond the column's range is a lint warning.)
    young = Const(1) if SGM_TRACK_AGE - k >= (1 << len(x)) - 1 else x <= SGM_TRACK_AGE - k
    for step in range(ahead):
        young = register(m, young, 1, f"sgm_left_young{k}_{at}_{step}")
    return young


def _history_read(owner, m, column, history, b0, k, at, enable=None, ahead=None):
    """b(p + k) into a register loaded at ``at`` (in round 0, or while ``enable``): entry
    (p + k) mod K of the history, or G(0) where p + k <= K; the multiplexer in ``ahead``
    clocks (default ``timing.left_history``)."""
    # The comparison and the history's address from the column ahead, and the history's
    # multiplexer in two clocks where the margins allow (the entry's low bits within
    # groups, registered, then the group): in front of the multiplexer they were census
    # 7x7 SGM's critical path (13.5 ns, ECP5), and the multiplexer in one clock was next
    # (9.9 ns, five LUT levels, at R = 10).
    slots = owner._slots
    ahead = owner.timing.left_history if ahead is None else ahead
    x = column(at - ahead)
    # The entry once per group of the history's multiplexer: one register into the
    # selects of all K = 32 entries was census 7x7 SGM's critical path at R = 10
    # (11.38 ns, 3 levels, 87.9 MHz).
    entry_bits = SGM_TRACK_AGE.bit_length() - 1
    by_pairs = ahead == SGM_HISTORY_PAIRS_CLOCKS
    groups = _pick_pair_groups(SGM_TRACK_AGE) if by_pairs else \
        _pick_groups(SGM_TRACK_AGE, entry_bits)
    entries = [replica(m, (x + k)[:entry_bits], f"sgm_left_history_at{k}_{g}",
                       unsigned(entry_bits), reset_less=True)
               for g in range(groups)]
    if by_pairs:
        tracked = _pick_by_pairs(m, history, entries[0], f"sgm_left_history{k}", entries)
    elif ahead >= 2:
        tracked = _pick(m, history, entries[0], f"sgm_left_history{k}", entries,
                        registered=ahead == 3)
    else:
        tracked = Array(history)[entries[0]]
    near = _young(m, column, k, at, ahead)
    return register(m, Mux(near, b0, tracked), len(b0), f"sgm_left_b{k}",
                    slots.first(at) if enable is None else enable)
