"""What the hardware builds, as pure functions of the parameters.

The register plans of the datapath units (lists of bool, see :func:`~.trees.register_plan`:
which levels end in a register; ``sum()`` of a plan is the unit's latency), the rows of the
windows and of the costs each cost unit computes, the copies of a window's centre, the
slices of a store word, the banks of a cost line buffer, the widths of the output word and
of a vertical sum. The components build what these say, and :mod:`.plan_timing` and
:mod:`.plan_memories` count with the same functions, so that the numbers cannot drift from
the hardware. What differs between transforms comes from their descriptions
(``params.TRANSFORM_SPECS``).
"""

from .trees import DEFAULT_EVERY, PAIRED_ADDER_BITS, popcount_plan, register_plan, sad_plan

__all__ = ["output_width", "transform_plan", "census_registers_compared",
           "SPACED_POPCOUNT_ABOVE", "SPACED_SAD_ABOVE", "cost_plan", "centre_copies",
           "STORE_SLICE_BITS", "store_slices", "cost_rows", "transformed_rows", "window_rows",
           "window_first_row", "window_pixels", "masks_after_compare", "vertical_bits",
           "vertical_plan", "horizontal_plan", "row_sum_plan", "BANK_CHOICE", "COST_BANK",
           "cost_banks", "choice_levels", "banked_read_clocks", "bank_choice_levels",
           "ROW_BANK", "ROW_BANK_DEEPEST",
           "row_banks"]


def output_width(params):
    """Width of ``m_axis_tdata``: the output disparity's bits (with F fractional ones) plus
    the valid flag, in whole bytes."""
    return 8 * -(-(params.output_disparity_bits + 1) // 8)


def _unit_plan(tree, params, every, depth):
    """Register plan of a unit over the k neighbours: ``tree`` "popcount" (of k bits),
    "sad" (of k absolute differences, see trees.sad_leaves) or None (one value: a
    reduction of ``params.REDUCTIONS``); ``depth`` levels of logic in front of it count
    against the register spacing, and the result is registered (``every`` > 0)."""
    registered = every > 0
    if tree == "popcount":
        return popcount_plan(params.neighbours, every, depth, registered)
    if tree == "sad":
        return sad_plan(params.neighbours, every, depth, registered,
                        params.lut_inputs)
    return register_plan(1, every, depth, registered)


def transform_plan(params, every=DEFAULT_EVERY, mask_after=False):
    """Register plan of ``params.transform``; ``sum()`` of it is the transform's latency.

    The comparisons or differences with the centre come first, and they are registered
    on their own: the centre pixel reaches all k of them, and that fanout plus a carry
    chain is a clock's worth of routing on ECP5 (8.2 ns for rank 7x7 with the popcount's
    full adders behind it). For a transform that counts its comparisons (rank) the plan's
    first entry is that register, then the popcount's plan; a sum of absolute differences
    (ext. rank) has the subtractions and inversions as the leaves of its tree (one level,
    then a register); a transform that keeps its k values (census, ext. census) is one
    level and the output register. Census with ``mask_after``
    (:func:`masks_after_compare`) registers the comparisons, then chooses the bits of the
    neighbours outside the frame, then the output register.
    """
    reduction = params.spec.transform_reduction
    if census_registers_compared(params, every, mask_after):
        return [True, True]
    if reduction == "popcount":
        return [every > 0] + popcount_plan(params.neighbours, every, 0, every > 0)
    return _unit_plan(reduction, params, every, 1)


def census_registers_compared(params, every, mask_after):
    """Whether a transform that keeps its comparison bits (census) registers them (with
    the flags) before the choice of the masked bits, then the output: a LUT behind the
    comparison's carry chain in the same clock was census 7x7's critical path (6.67 ns,
    ECP5)."""
    spec = params.spec
    return spec.compares and spec.transform_reduction is None and mask_after and every > 0


#: Neighbours above which the census cost's popcount registers every second adder level,
#: not every level. Census is flip-flop-bound on the ECP5 from 17x17 on: at 17x17 the
#: thirty popcounts' registers were 22,680 of 70,503 flip-flops (84 % of the 85k, its LUTs
#: at 79 %), and those cores' clocks are limited by the input stage's wires (8.5 ns and
#: more), not by the 6.7 ns two adder levels take.
SPACED_POPCOUNT_ABOVE = 256


#: Neighbours above which ext. census's sum of absolute differences takes its first
#: register one adder level later (spacing 3; the latency is the same). Yosys then maps
#: the differences' inversions and two adder levels into Cyclone V's ALM compressors (a
#: 360-pair sum alone: 10,290 ALUTs against 11,295), which ECP5's LUT4s cannot hold (48
#: pairs: 1,704 LUT4 against 1,560, 4.6 LUT levels against 3.6). From 13x13 on ext. census
#: is too large for the ECP5-85k, the largest ECP5 (122 % of its LUTs at 13x13, 159 % at
#: 15x15), and at 19x19 it was 4.1 % over the paper's EP2S180 (138,648 ALUTs now, within).
#: Arranged for 6-input LUTs (``lut_inputs`` 6) the sum is smaller still with the usual
#: spacing, and the wider one does not pay: 8,877 ALUTs and 3.6 levels against 10,369 and
#: 9.3 (360 pairs, Cyclone V).
SPACED_SAD_ABOVE = 120


def cost_plan(params, every=DEFAULT_EVERY):
    """Register plan of the matching cost; ``sum()`` of it is the cost unit's latency.

    The census cost's XOR in front of the popcount is one LUT level, far shorter than an
    adder level, and is not counted against the spacing, and its adder levels are
    registered one by one; the ext. census sum of absolute differences counts its
    subtraction itself; rank and ext. rank costs are one absolute difference
    (``TransformSpec.cost_reduction``).
    """
    tree = params.spec.cost_reduction
    if (tree == "sad" and every and params.neighbours > SPACED_SAD_ABOVE
            and params.lut_inputs < 6):
        every = max(every, 3)
    if tree == "popcount" and params.neighbours <= SPACED_POPCOUNT_ABOVE:
        # A register after every adder level: two of the popcount's short adders in one
        # clock were census 9x9's critical path once the control paths were cut (6.7 ns,
        # five LUT levels, ECP5).
        every = min(every, 1)
    if tree is None and every and params.transform_bits > PAIRED_ADDER_BITS:
        # Both differences registered, then the choice: a wide comparison, two
        # subtractions and the multiplexer in one clock were 7.7 ns (ext. rank 9x9, ECP5).
        return [True, True]
    return _unit_plan(tree, params, every, 1 if tree is None else 0)


def centre_copies(params):
    """Copies of each window's centre pixel, one per ``TransformSpec.centre_fanout``
    neighbours of the transform.

    The centre reaches all k comparisons (or differences) of a transform; as one register
    that fan-out was 5 ns of routing on ECP5 (rank 7x7). Each copy is loaded by a clock
    enable from a slot counter of its own, which keeps synthesis from merging the copies;
    with R = 1 there is no slot to count, and one register it stays.
    """
    if params.rounds == 1:
        return 1
    return -(-params.neighbours // params.spec.centre_fanout)


#: Widest slice of a right-transform store with address counters of its own: an address
#: register driving a whole store (census 9x9: 60 LUT RAM cells) was 7 ns of routing on
#: ECP5.
STORE_SLICE_BITS = 32


def store_slices(width):
    """Widths of the slices a store word of ``width`` bits is cut into: as equal as can
    be, none wider than :data:`STORE_SLICE_BITS`."""
    count = -(-width // STORE_SLICE_BITS)
    return [width // count + (k < width % count) for k in range(count)]


def cost_rows(params):
    """Rows whose costs each cost unit computes: A when the rows above are kept as
    transformed pixels or as pixels (``stored_rows`` "transforms" or "pixels"), else 1."""
    if params.agg_radius and params.stored_rows in ("transforms", "pixels"):
        return params.aggregation
    return 1


def transformed_rows(params):
    """Rows whose windows are transformed per position: A with ``stored_rows ==
    "pixels"`` (the rows above are transformed again from pixels), else 1."""
    return cost_rows(params) if params.stored_rows == "pixels" else 1


def window_rows(params):
    """Rows of the input stage's window: B, or B + A - 1 when the rows above are
    transformed again from pixels (the A windows of a column, one below the other)."""
    return params.block + transformed_rows(params) - 1


def window_first_row(params, k):
    """First row, in the input stage's window of :func:`window_rows` rows (top row 0),
    of the window k rows above the newest."""
    return transformed_rows(params) - 1 - k


def window_pixels(params):
    """Pixels of the window the input stage hands the calculation stage: the A windows'
    own masked pixels, or with :func:`masks_after_compare` the rows they share."""
    if masks_after_compare(params):
        return window_rows(params) * params.block
    return transformed_rows(params) * params.block * params.block


def masks_after_compare(params):
    """Whether the A windows of a column share one unmasked window of pixels, and the
    transforms mask their comparisons instead (``Transform(mask_after=True)``).

    Transforms of comparisons (census, rank: ``TransformSpec.compares``) with
    ``stored_rows == "pixels"``: a neighbour outside the frame is 0,
    and its bit (0 < centre) is centre != 0, one LUT after the comparison (census: after
    the comparison's register, see :func:`transform_plan`). Masking the
    pixels instead keeps A masked copies of overlapping rows, twice (the window register
    and the one by the comparisons): census 11x11 held 11,616 flip-flops there, against
    4,576 for one shared window and 726 for its flags (ECP5 placement: docs/hardware.md).
    """
    return params.spec.compares and transformed_rows(params) > 1


def vertical_bits(params):
    """Width of a vertical (column) sum of A costs."""
    return (params.max_cost * params.aggregation).bit_length()


def vertical_plan(params, every=DEFAULT_EVERY):
    """Register plan of the vertical sum of A stored costs; their masks are a level of
    logic in front of the adders."""
    return register_plan(params.aggregation, every, 1, True, params.cost_bits)


def horizontal_plan(params, every=DEFAULT_EVERY):
    """Register plan of the horizontal sum of 2a + 1 vertical sums; their masks are a
    level of logic in front of the adders."""
    return register_plan(2 * params.agg_radius + 1, every, 1, True, vertical_bits(params))


def row_sum_plan(params, every=DEFAULT_EVERY):
    """Register plan of a cost unit's sum of its A row costs (rows above kept as
    transforms); the masks are a level of logic in front of the adders."""
    return register_plan(cost_rows(params), every, 1, True, params.cost_bits)


#: Banks chosen among in one clock: a 4:1 multiplexer is a LUT4 pair and a PFUMX on ECP5.
#: A unit's ten banks chosen in one clock were ext. census 7x7's critical path (11.3 ns,
#: four LUT levels, 88.2 MHz); more banks are chosen in a registered tree of such choices.
BANK_CHOICE = 4


#: Words of one bank of a cost line buffer (one ECP5 DP16KD at 36 bits, two Cyclone V
#: M10K at 20): the W*R words of a unit are cut into banks of their own, each with its
#: output register, and the bank is chosen behind those registers. One memory W*R deep was
#: a cascade of block RAMs with the choice in front of the first register (ext. census 7x7
#: on ECP5: nine DP16KD per unit, 70 MHz).
COST_BANK = 512


def cost_banks(params):
    """Depths of the banks of one unit's cost line buffer (W*R words in all)."""
    words = params.width * params.rounds
    full, rest = divmod(words, COST_BANK)
    return [COST_BANK] * full + ([rest] if rest else [])


def choice_levels(banks):
    """Registered levels of the choice among ``banks`` banks: level l chooses by digit l of
    the bank's index in base :data:`BANK_CHOICE` (one level for up to ``BANK_CHOICE`` banks,
    or a single bank)."""
    levels = 1
    while banks > BANK_CHOICE:
        levels, banks = levels + 1, -(-banks // BANK_CHOICE)
    return levels


def banked_read_clocks(banks):
    """Clocks from :func:`~.banks.banked_memory`'s early read address to its word, for a
    memory in ``banks`` banks: the address register, the read and the block RAM's output
    register, and with several banks a clock more for the register behind each bank's and
    one per level of the bank's choice."""
    return 3 + (1 + choice_levels(banks) if banks > 1 else 0)


def bank_choice_levels(params):
    """Registered levels of the choice of a unit's cost line buffer bank."""
    return choice_levels(len(cost_banks(params)))


#: Shallowest and deepest bank of SGM's path rows: a DP16KD holds 512 x 36, 1K x 18, 2K x 9,
#: 4K x 4, 8K x 2 or 16K x 1 bits, so a bank twice as deep takes its word in half as many
#: bits per block RAM.
ROW_BANK, ROW_BANK_DEEPEST = 512, 16384


def row_banks(params):
    """Depths of the banks of SGM's path rows (W*R words, ``per_round`` lanes per word):
    the shallowest power-of-two depth from :data:`ROW_BANK` that needs at most
    :data:`BANK_CHOICE` banks (one level of choice), up to :data:`ROW_BANK_DEEPEST`.

    The rows' words are wide (top and top-left: 2 D/R path costs), so every bank is a row
    of block RAMs and every level of the choice a multiplexer as wide as the word: census
    5x5 SGM at 1280 x 720, D = 64, R = 4 in ten 512-word banks (three levels) did not route
    on the ECP5-85k (congestion at the block RAMs with a fifth of the LUTs in use); in
    three banks of 2K x 9 it takes about as many DP16KD."""
    words = params.width * params.rounds
    depth = ROW_BANK
    while -(-words // depth) > BANK_CHOICE and depth < ROW_BANK_DEEPEST:
        depth *= 2
    full, rest = divmod(words, depth)
    return [depth] * full + ([rest] if rest else [])
