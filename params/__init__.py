"""The parameter object and the user-facing errors that golden/, hdl/, gen/ and sim/ share.

A neutral package (it imports nothing of the project), so that the golden model, the
hardware, the command line and the co-simulation can all depend on it without depending
on each other. Every entry point builds a :class:`StereoParams` first; its constructor
checks what every part needs (the algorithm's parameters and the frame size), so the
golden model, the hardware generator and the co-simulation reject those configurations
with the same message. What only one part needs is checked there: the hardware's size
limits in :func:`npstereo.hdl.plan.check_buildable`, image contents in the golden model's
loaders and pipeline, file names in the commands.

The transforms are described in :mod:`.transforms`, semi-global aggregation's paths,
penalties and defaults in :mod:`.sgm`; everything is importable from here.
"""

from dataclasses import dataclass, fields, replace

from .cost_terms import (AD3_DEFAULT_P2, COST_TERMS, check_cost_term, term_max)
from .errors import ParameterError, UserError, is_int, is_integral
from .sgm import (P2_ADAPT_OFF, SGM, SGM_DEFAULT_ADAPT, SGM_DEFAULT_P1, SGM_DEFAULT_P2,
                  SGM_MAX_ADAPT, SGM_PATH_COUNT, SGM_PATH_STEPS, SGM_PATHS, SGM_RECOMMENDED,
                  SGM_LEFT_P1_PARITY, SGM_ROW_PATHS, SGM_TRACK_AGE, SGM_TRACK_STEPS,
                  check_penalties,
                  check_sgm_paths, max_path_penalty, sgm_left_cost_bits, sgm_left_loop_bits,
                  sgm_path_cost_bits, sgm_path_steps, sgm_summed_cost_bits)
from .transforms import (REDUCTIONS, TRANSFORM_SPECS, TRANSFORMS, TransformSpec,
                         check_transform_table)

__all__ = ["TransformSpec", "TRANSFORM_SPECS", "TRANSFORMS", "REDUCTIONS",
           "check_transform_table", "LINE_BUFFERS", "LUT_INPUTS", "SGM", "SGM_PATH_STEPS",
           "SGM_PATHS", "SGM_PATH_COUNT", "SGM_ROW_PATHS", "sgm_path_steps", "check_sgm_paths",
           "SGM_DEFAULT_P1", "SGM_DEFAULT_P2", "SGM_DEFAULT_ADAPT", "SGM_MAX_ADAPT",
           "P2_ADAPT_OFF", "SGM_RECOMMENDED", "UserError", "ParameterError", "StereoParams",
           "max_path_penalty", "check_penalties", "SGM_TRACK_STEPS", "SGM_TRACK_AGE",
           "SGM_LEFT_P1_PARITY", "sgm_path_cost_bits", "sgm_left_cost_bits", "sgm_left_loop_bits",
           "sgm_summed_cost_bits", "MEDIAN_FILL", "MAX_SUBPIXEL_BITS", "COST_TERMS",
           "default_p2"]

#: What the hardware keeps of the rows above for the vertical aggregation: the matching
#: costs of the A-1 rows (D costs per column), or the transformed pixels of both images
#: (the costs of those rows are computed again, A cost units per disparity); "auto" takes
#: whichever is cheaper overall for the transform (docs/hardware.md).
LINE_BUFFERS = ("auto", "costs", "transforms", "pixels")

#: LUT sizes the hardware's sums of absolute differences are arranged for: 4 (ECP5, iCE40,
#: Gowin: the inverted differences go to adders) or 6 (Intel ALMs, AMD/Xilinx: three
#: differences at a time go to 3:2 compressors whose LUTs also invert them).
LUT_INPUTS = (4, 6)

#: The 3x3 median (``StereoParams.median``) fills an invalid pixel from this many valid
#: values of its window, a majority of the nine (docs/semantics.md, "3x3 median").
MEDIAN_FILL = 5

#: Most fractional bits of the sub-pixel disparity (users of stereo cameras ask for 3-5;
#: OpenCV's StereoSGBM gives 4).
MAX_SUBPIXEL_BITS = 5


@dataclass(frozen=True)
class StereoParams:
    """Configuration of one stereo core and of its golden model.

    Parameters
    ----------
    transform : str
        One of :data:`TRANSFORMS`.
    block : int
        Transform window size B (odd, >= 3); the window is B x B without its centre.
    disparities : int
        Disparity range D (>= 2): disparities 0 .. D-1 are searched.
    rounds : int
        Calculation rounds R; each round evaluates D/R disparities. Must divide D.
    aggregation : int or str
        Cost aggregation: an A x A box (A odd, >= 1; the paper uses 3) or :data:`SGM`,
        semi-global aggregation along :data:`SGM_PATHS` (docs/semantics.md).
    lr_threshold : int or None
        Left/right consistency threshold T (>= 0); ``None`` disables the check.
    width, height : int or None
        Frame size. Required by the hardware; the golden model takes it from the images.
    line_buffer : str
        One of :data:`LINE_BUFFERS`: the hardware's memory for the vertical aggregation.
        It changes resources, never a result.
    lut_inputs : int
        One of :data:`LUT_INPUTS`: the inputs of the target fabric's LUTs, which the sums of
        absolute differences (the ext. census cost, the ext. rank transform) are arranged
        for. It changes resources, never a result.
    p1, p2 : int or None
        SGM penalties, 0 <= P1 <= P2 <= :func:`max_path_penalty` (Cmax). With
        ``aggregation="sgm"`` a ``None`` becomes :data:`SGM_DEFAULT_P1` /
        :data:`SGM_DEFAULT_P2`, so the object always holds the values in use; with a box
        both must be ``None``.
    p2_adapt : int or None
        SGM adaptive-P2 threshold exponent t, 1 .. :data:`SGM_MAX_ADAPT`, or
        :data:`P2_ADAPT_OFF` (0) for a constant P2. With ``aggregation="sgm"`` ``None``
        becomes :data:`SGM_DEFAULT_ADAPT` (adaptive P2 is on by default); with a box it
        must be ``None``.
    median : bool
        A 3x3 median of the output map after the L/R check (docs/semantics.md, "3x3
        median"), for the box and SGM alike; off by default.
    subpixel_bits : int
        F, 0 .. :data:`MAX_SUBPIXEL_BITS`: fractional bits of the output disparity (a
        parabola through the winner's summed costs and its neighbours', docs/semantics.md
        "Sub-pixel disparity"); 0 is the whole levels of the plain WTA.
    cost_term : str or None
        A term of :data:`COST_TERMS` added to the matching cost (census with SGM only;
        docs/semantics.md "The ad3 cost term"); it raises Cmax and, when P2 is not given,
        makes the default P2 :func:`default_p2`'s. ``None`` (default): the transform's cost.
    fifth_path : bool
        SGM only: a fifth path, right to left along the row (the left path mirrored,
        docs/semantics.md "The fifth path"), summed with the four raster-order paths; off
        by default.
    """

    transform: str = "census"
    block: int = 9
    disparities: int = 100
    rounds: int = 1
    aggregation: int | str = 3
    lr_threshold: int | None = 3
    width: int | None = None
    height: int | None = None
    line_buffer: str = "auto"
    lut_inputs: int = 4
    p1: int | None = None
    p2: int | None = None
    p2_adapt: int | None = None
    median: bool = False
    subpixel_bits: int = 0
    cost_term: str | None = None
    fifth_path: bool = False

    def __repr__(self):
        # The dataclass's form, without subpixel_bits while it is 0, cost_term while it
        # is None and fifth_path while it is off: repr() is the report cache's key, and
        # every configuration without them keeps its key.
        shown = [f for f in fields(self) if getattr(self, f.name) or f.name not in
                 ("subpixel_bits", "cost_term", "fifth_path")]
        return (f"{type(self).__qualname__}("
                + ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in shown) + ")")

    def __post_init__(self):
        if self.transform not in TRANSFORMS:
            raise ParameterError(
                f"transform must be one of {', '.join(TRANSFORMS)}, not {self.transform!r}")
        if not is_int(self.block) or self.block < 3 or self.block % 2 == 0:
            raise ParameterError(f"block size must be an odd integer >= 3, not {self.block!r}")
        if not is_int(self.disparities) or self.disparities < 2:
            raise ParameterError(
                f"disparities must be an integer >= 2, not {self.disparities!r}")
        if not is_int(self.rounds) or self.rounds < 1:
            raise ParameterError(f"rounds must be an integer >= 1, not {self.rounds!r}")
        if self.disparities % self.rounds != 0:
            raise ParameterError(
                f"rounds must divide disparities ({self.disparities}), not {self.rounds!r}")
        check_cost_term(self.cost_term, self.transform, self.aggregation == SGM,
                        self.aggregation)
        if self.aggregation == SGM:
            self._resolve_penalties()
        else:
            if (not is_int(self.aggregation) or self.aggregation < 1
                    or self.aggregation % 2 == 0):
                raise ParameterError(f"aggregation must be an odd window size >= 1 or "
                                     f"{SGM!r}, not {self.aggregation!r}")
            for name in ("p1", "p2", "p2_adapt"):
                if getattr(self, name) is not None:
                    raise ParameterError(
                        f"{name} is an SGM parameter: it needs aggregation {SGM!r}, not a "
                        f"{self.aggregation}x{self.aggregation} box")
        if self.lr_threshold is not None and (
                not is_int(self.lr_threshold) or self.lr_threshold < 0):
            raise ParameterError(
                f"lr threshold must be an integer >= 0 (or disabled), not {self.lr_threshold!r}")
        if self.width is not None:
            if not is_int(self.width) or self.width <= self.first_valid_column:
                raise ParameterError(
                    f"image width must be an integer > {self.first_valid_column} for "
                    f"{self.disparities} disparities (first valid column "
                    f"{self.first_valid_column}), not {self.width!r}")
        if self.height is not None:
            if not is_int(self.height) or self.height < 1:
                raise ParameterError(f"image height must be an integer >= 1, not {self.height!r}")
        if self.line_buffer not in LINE_BUFFERS:
            raise ParameterError(f"line buffer must be one of {', '.join(LINE_BUFFERS)}, "
                                 f"not {self.line_buffer!r}")
        if not is_int(self.lut_inputs) or self.lut_inputs not in LUT_INPUTS:
            raise ParameterError(f"lut inputs must be one of "
                                 f"{', '.join(map(str, LUT_INPUTS))}, not {self.lut_inputs!r}")
        if not isinstance(self.median, bool):
            raise ParameterError(f"median must be True or False, not {self.median!r}")
        if (not is_int(self.subpixel_bits)
                or not 0 <= self.subpixel_bits <= MAX_SUBPIXEL_BITS):
            raise ParameterError(f"subpixel bits must be an integer 0 .. {MAX_SUBPIXEL_BITS}, "
                                 f"not {self.subpixel_bits!r}")
        if not isinstance(self.fifth_path, bool):
            raise ParameterError(f"fifth path must be True or False, not {self.fifth_path!r}")
        if self.fifth_path and not self.is_sgm:
            raise ParameterError(f"the fifth path is an SGM path: it needs aggregation "
                                 f"{SGM!r}, not a {self.aggregation}x{self.aggregation} box")

    def _resolve_penalties(self):
        """Validate the SGM penalties and store the defaults in place of ``None``."""
        p1 = SGM_DEFAULT_P1 if self.p1 is None else self.p1
        p2 = default_p2(self.cost_term) if self.p2 is None else self.p2
        adapt = SGM_DEFAULT_ADAPT if self.p2_adapt is None else self.p2_adapt
        try:
            check_penalties(self.max_cost, p1, p2)
        except ParameterError as error:
            # A P2 error (P1 itself is fine) may be about a default the user never typed:
            # say where the number came from.
            p1_fine = is_integral(p1) and p1 >= 0
            if p1_fine and (self.p1 is None or self.p2 is None):
                raise ParameterError(f"{error} (SGM defaults P1 = {SGM_DEFAULT_P1}, "
                                     f"P2 = {default_p2(self.cost_term)})") from None
            raise
        off = is_integral(adapt) and adapt == P2_ADAPT_OFF
        check_penalties(self.max_cost, p1, p2, None if off else adapt)
        # Frozen: the resolved values are set once, here. Plain ints, so that repr() (the
        # report cache's key) and JSON do not depend on how a caller spelled the number.
        for name, value in (("p1", p1), ("p2", p2), ("p2_adapt", adapt)):
            object.__setattr__(self, name, int(value))

    def with_size(self, width, height):
        """The same configuration for a ``width`` x ``height`` frame (validated)."""
        return replace(self, width=width, height=height)

    def replace(self, **changes):
        """A validated copy with ``changes`` applied."""
        return replace(self, **changes)

    # Geometry -------------------------------------------------------------------------

    @property
    def radius(self):
        """Transform window radius r = (B-1)/2."""
        return (self.block - 1) // 2

    @property
    def is_sgm(self):
        """Semi-global aggregation instead of the A x A box."""
        return self.aggregation == SGM

    @property
    def agg_radius(self):
        """Aggregation window radius a = (A-1)/2; 0 for SGM (no window)."""
        return 0 if self.is_sgm else (self.aggregation - 1) // 2

    @property
    def neighbours(self):
        """k = B*B - 1, the number of neighbours compared with the centre."""
        return self.block * self.block - 1

    @property
    def per_round(self):
        """Disparities evaluated per calculation round, D/R."""
        return self.disparities // self.rounds

    @property
    def first_valid_column(self):
        """Columns left of this have no full disparity range and are invalid.

        ``D - 1 + max(1, a)``: x >= D as in the paper for A <= 3, and for wider aggregation
        windows also every right-image pixel the aggregation touches lies inside the image.
        SGM has no window (a = 0): x >= D.
        """
        return self.disparities - 1 + max(1, self.agg_radius)

    @property
    def spec(self):
        """The :class:`TransformSpec` of ``transform``."""
        return TRANSFORM_SPECS[self.transform]

    @property
    def stored_rows(self):
        """What the hardware stores of the rows above: "costs", "transforms" or "pixels".

        "pixels" keeps only A - 1 more rows of pixels and transforms the rows above again;
        "transforms" keeps their transformed pixels; "costs" their costs. "auto" takes the
        transform's choice (``TransformSpec.auto_stored_rows``).
        """
        if self.line_buffer != "auto":
            return self.line_buffer
        return self.spec.auto_stored_rows

    @property
    def lr_check(self):
        return self.lr_threshold is not None

    # Bit widths (see docs/semantics.md) -----------------------------------------------

    @property
    def transform_bits(self):
        """Width of one transformed pixel."""
        return self.spec.transform_bits(self.neighbours)

    @property
    def max_cost(self):
        """Largest matching cost of one pixel pair: the transform's, plus the largest
        value of the cost term if there is one (Cmax of docs/semantics.md)."""
        return self.spec.max_cost(self.neighbours) + term_max(self.cost_term)

    @property
    def cost_bits(self):
        return self.max_cost.bit_length()

    @property
    def aggregated_cost_bits(self):
        """Width of the aggregated cost S that the winner-takes-all compares.

        Box: bitlen(A^2 Cmax). SGM: the sum of the four path costs,
        bitlen(K Cmax + P2 + 3 (Cmax + P2)), or of five with the fifth path,
        bitlen(2 (K Cmax + P2) + 3 (Cmax + P2)) (:func:`~.sgm.sgm_summed_cost_bits`).
        """
        if self.is_sgm:
            return sgm_summed_cost_bits(self.max_cost, self.p2, self.fifth_path)
        return (self.max_cost * self.aggregation * self.aggregation).bit_length()

    @property
    def path_cost_bits(self):
        """SGM: width of one path cost L_r(p, d) of the paths from the row above and of its
        minimum, bitlen(Cmax + P2); ``None`` for a box."""
        return sgm_path_cost_bits(self.max_cost, self.p2) if self.is_sgm else None

    @property
    def left_cost_bits(self):
        """SGM: width of the left path's L(p, d), bitlen(K Cmax + P2); ``None`` for a box."""
        return sgm_left_cost_bits(self.max_cost, self.p2) if self.is_sgm else None

    @property
    def left_loop_bits(self):
        """SGM: width n of the hardware's left path cost kept modulo 2^n; ``None`` for a
        box."""
        if not self.is_sgm:
            return None
        return sgm_left_loop_bits(self.max_cost, self.p1, self.p2)

    @property
    def disparity_bits(self):
        return (self.disparities - 1).bit_length()

    @property
    def output_disparity_bits(self):
        """Width of the output disparity: the whole levels and F fractional bits (the
        value is d 2^F + o <= (D - 1) 2^F, docs/semantics.md "Sub-pixel disparity")."""
        return self.disparity_bits + self.subpixel_bits

    def describe(self):
        """One line for headers, logs and file names' documentation."""
        lr = "off" if self.lr_threshold is None else str(self.lr_threshold)
        size = "" if self.width is None else f" {self.width}x{self.height}"
        buffer = "" if self.line_buffer == "auto" else f" LB={self.line_buffer}"
        lut = "" if self.lut_inputs == 4 else f" LUT{self.lut_inputs}"
        median = " median" if self.median else ""
        fraction = f" F={self.subpixel_bits}" if self.subpixel_bits else ""
        term = f"+{self.cost_term}" if self.cost_term else ""
        return (f"{self.transform}{term} {self.block}x{self.block} D={self.disparities} "
                f"R={self.rounds} {self.describe_aggregation()} LR={lr}{median}{size}{buffer}"
                f"{lut}{fraction}")

    def describe_aggregation(self):
        """The aggregation alone: ``A=3``, or ``SGM P1=24 P2=79 t=5`` (``t=off``)."""
        if not self.is_sgm:
            return f"A={self.aggregation}"
        adapt = "off" if self.p2_adapt == P2_ADAPT_OFF else str(self.p2_adapt)
        fifth = " 5 paths" if self.fifth_path else ""
        return f"SGM P1={self.p1} P2={self.p2} t={adapt}{fifth}"


def default_p2(cost_term):
    """SGM's default P2 for ``cost_term``: :data:`SGM_DEFAULT_P2`, or with ``ad3`` the
    smaller one that keeps census 7x7's path cost at 7 bits (``cost_terms.AD3_DEFAULT_P2``);
    the one place the term changes a default."""
    return SGM_DEFAULT_P2 if cost_term is None else AD3_DEFAULT_P2
