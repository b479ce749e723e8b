"""Does a synthesis result fit the ECP5 LFE5U-85F, and how full is it?

Place and route of a design above the device's capacity cannot succeed, and nextpnr takes
minutes to say so (or hangs in the router); the check here answers from the synthesis
counts at once.
"""

__all__ = ["ECP5_85K", "ecp5_utilisation", "fit_message"]

#: Resources of the LFE5U-85F (the part ``nextpnr-ecp5 --85k`` places on).
ECP5_85K = {
    # 41,820 slices of two LUT4 and two flip-flops: Lattice ECP5 and ECP5-5G Family Data
    # Sheet (FPGA-DS-02012), Table 1.1 "84K LUTs" for the LFE5U-85; the exact count is
    # nextpnr-ecp5's device database for the 85k (41,820 TRELLIS_SLICE, its "Device
    # utilisation" report), two LUT4 and two FFs per slice (data sheet, section 2.2 PFU).
    "LUT4": 83640,
    "FF": 83640,
    # Data sheet Table 1.1: 208 sysMEM blocks of 18 kbit (3,744 kbit) for the LFE5U-85.
    "DP16KD": 208,
    # Data sheet Table 1.1: 156 18x18 multipliers (MULT18X18D) for the LFE5U-85.
    "MULT18X18D": 156,
    # Data sheet Table 1.1: 669 kbit distributed RAM = 10,455 PFUs x one 16x4 RAM each
    # (a TRELLIS_DPR16X4 takes slices 0 and 1 of a PFU for the RAM and slice 2 for its
    # write port; section 2.2.1 of the data sheet).
    "TRELLIS_DPR16X4": 10455,
}

#: LUT4 sites a TRELLIS_DPR16X4 takes away from logic (three slices, see above).
_LUTS_PER_DPR16X4 = 6


def ecp5_utilisation(result):
    """Utilisation (percent) of the LFE5U-85F by an ``ecp5`` synthesis result.

    Parameters
    ----------
    result : dict
        A result of :func:`npstereo.gen.synth.synthesise` for ``ecp5`` (``logic`` in LUT4
        including two per ``CCU2C``, ``registers``, ``block_rams``, ``lut_rams``,
        ``dsps``).

    Returns
    -------
    dict
        Percent per resource: ``LUT`` (logic plus the LUT sites of LUT RAMs), ``FF``,
        ``DP16KD``, ``DSP`` and ``LUTRAM``, rounded to 0.1.
    """
    luts = result["logic"] + _LUTS_PER_DPR16X4 * result.get("lut_rams", 0)
    used = {"LUT": (luts, "LUT4"), "FF": (result["registers"], "FF"),
            "DP16KD": (result["block_rams"], "DP16KD"),
            "DSP": (result.get("dsps", 0), "MULT18X18D"),
            "LUTRAM": (result.get("lut_rams", 0), "TRELLIS_DPR16X4")}
    return {name: round(100.0 * count / ECP5_85K[resource], 1)
            for name, (count, resource) in used.items()}


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
