"""The parameter object and the user-facing errors that golden/, hdl/, gen/ and sim/ share.

A neutral module (it imports nothing of the project), so that the golden model, the
hardware, the command line and the co-simulation can all depend on it without depending
on each other. Every entry point builds a :class:`StereoParams` first; its constructor
checks what every part needs (the algorithm's parameters and the frame size), so the
golden model, the hardware generator and the co-simulation reject those configurations
with the same message. What only one part needs is checked there: the hardware's size
limits in :func:`npstereo.hdl.plan.check_buildable`, image contents in the golden model's
loaders and pipeline, file names in the commands.
"""

from dataclasses import dataclass, replace

__all__ = ["TRANSFORMS", "LINE_BUFFERS", "UserError", "ParameterError", "StereoParams"]

#: Transform names as the command line spells them, in the paper's order.
TRANSFORMS = ("rank", "census", "ext-rank", "ext-census")

#: What the hardware keeps of the rows above for the vertical aggregation: the matching
#: costs of the A-1 rows (D costs per column), or the transformed pixels of both images
#: (the costs of those rows are computed again, A cost units per disparity); "auto" takes
#: whichever is cheaper overall for the transform (docs/hardware.md).
LINE_BUFFERS = ("auto", "costs", "transforms")


class UserError(Exception):
    """Anything the user can fix: a bad parameter, a missing or malformed file, a missing tool.

    The message is one line naming what is wrong and what is allowed; the command line
    prints it as is and exits with code 2, without a traceback.
    """


class ParameterError(UserError, ValueError):
    """A parameter outside what the model and the hardware support.

    The message is one line naming the parameter, the offending value and what is allowed;
    the command line prints it as is and exits with code 2.
    """


def _is_int(value):
    """A true integer: ``bool`` is an ``int`` subclass, but ``block=True`` is a mistake."""
    return isinstance(value, int) and not isinstance(value, bool)


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
    aggregation : int
        Cost aggregation window size A (odd, >= 1); the paper uses 3.
    lr_threshold : int or None
        Left/right consistency threshold T (>= 0); ``None`` disables the check.
    width, height : int or None
        Frame size. Required by the hardware; the golden model takes it from the images.
    line_buffer : str
        One of :data:`LINE_BUFFERS`: the hardware's memory for the vertical aggregation.
        It changes resources, never a result.
    """

    transform: str = "census"
    block: int = 9
    disparities: int = 100
    rounds: int = 1
    aggregation: int = 3
    lr_threshold: int | None = 3
    width: int | None = None
    height: int | None = None
    line_buffer: str = "auto"

    def __post_init__(self):
        if self.transform not in TRANSFORMS:
            raise ParameterError(
                f"transform must be one of {', '.join(TRANSFORMS)}, not {self.transform!r}")
        if not _is_int(self.block) or self.block < 3 or self.block % 2 == 0:
            raise ParameterError(f"block size must be an odd integer >= 3, not {self.block!r}")
        if not _is_int(self.disparities) or self.disparities < 2:
            raise ParameterError(
                f"disparities must be an integer >= 2, not {self.disparities!r}")
        if not _is_int(self.rounds) or self.rounds < 1:
            raise ParameterError(f"rounds must be an integer >= 1, not {self.rounds!r}")
        if self.disparities % self.rounds != 0:
            raise ParameterError(
                f"rounds must divide disparities ({self.disparities}), not {self.rounds!r}")
        if (not _is_int(self.aggregation) or self.aggregation < 1
                or self.aggregation % 2 == 0):
            raise ParameterError(
                f"aggregation size must be an odd integer >= 1, not {self.aggregation!r}")
        if self.lr_threshold is not None and (
                not _is_int(self.lr_threshold) or self.lr_threshold < 0):
            raise ParameterError(
                f"lr threshold must be an integer >= 0 (or disabled), not {self.lr_threshold!r}")
        if self.width is not None:
            if not _is_int(self.width) or self.width <= self.first_valid_column:
                raise ParameterError(
                    f"image width must be an integer > {self.first_valid_column} for "
                    f"{self.disparities} disparities (first valid column "
                    f"{self.first_valid_column}), not {self.width!r}")
        if self.height is not None:
            if not _is_int(self.height) or self.height < 1:
                raise ParameterError(f"image height must be an integer >= 1, not {self.height!r}")
        if self.line_buffer not in LINE_BUFFERS:
            raise ParameterError(f"line buffer must be one of {', '.join(LINE_BUFFERS)}, "
                                 f"not {self.line_buffer!r}")

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
    def agg_radius(self):
        """Aggregation window radius a = (A-1)/2."""
        return (self.aggregation - 1) // 2

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
        """
        return self.disparities - 1 + max(1, self.agg_radius)

    @property
    def stored_rows(self):
        """What the hardware stores of the rows above: "costs" or "transforms".

        "auto" keeps transformed pixels, except for the extended census, whose cost (k
        byte-wise absolute differences and their sum) is too large to compute A times.
        """
        if self.line_buffer != "auto":
            return self.line_buffer
        return "costs" if self.transform == "ext-census" else "transforms"

    @property
    def lr_check(self):
        return self.lr_threshold is not None

    # Bit widths (see docs/semantics.md) -----------------------------------------------

    @property
    def transform_bits(self):
        """Width of one transformed pixel."""
        k = self.neighbours
        return {
            "rank": k.bit_length(),
            "census": k,
            "ext-rank": (k * 255).bit_length(),
            "ext-census": 8 * k,
        }[self.transform]

    @property
    def max_cost(self):
        """Largest matching cost of one pixel pair."""
        k = self.neighbours
        return k if self.transform in ("rank", "census") else 255 * k

    @property
    def cost_bits(self):
        return self.max_cost.bit_length()

    @property
    def aggregated_cost_bits(self):
        return (self.max_cost * self.aggregation * self.aggregation).bit_length()

    @property
    def disparity_bits(self):
        return (self.disparities - 1).bit_length()

    def describe(self):
        """One line for headers, logs and file names' documentation."""
        lr = "off" if self.lr_threshold is None else str(self.lr_threshold)
        size = "" if self.width is None else f" {self.width}x{self.height}"
        buffer = "" if self.line_buffer == "auto" else f" LB={self.line_buffer}"
        return (f"{self.transform} {self.block}x{self.block} D={self.disparities} "
                f"R={self.rounds} A={self.aggregation} LR={lr}{size}{buffer}")
