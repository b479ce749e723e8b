"""Simulation models of the cells a mapped netlist instantiates, for Icarus and Verilator.

The models are Yosys's own (the ``share`` folder of the installed ``pyosys`` wheel, the
same Yosys that mapped the netlist):

``ecp5``
    ``lattice/cells_sim_ecp5.v`` (LUT4, CCU2C, PFUMX, L6MUX21, TRELLIS_FF,
    TRELLIS_DPR16X4, ...) with its includes inlined once, and the project's DP16KD model
    :data:`DP16KD_MODEL` instead of Yosys's DP16KD, which is an empty module.
``cyclonev``
    ``intel_alm/common/{alm,dff,mem,dsp,misc}_sim.v`` (MISTRAL_ALUT*, MISTRAL_ALUT_ARITH,
    MISTRAL_FF, MISTRAL_MLAB, MISTRAL_M10K, multipliers, MISTRAL_CLKBUF). ``cyclonev`` is
    left undefined:
    it only enables the ``specify`` timing blocks, which zero-delay simulation ignores.
"""

import re
import sys
from pathlib import Path

from ...params import UserError

__all__ = ["FAMILIES", "DP16KD_MODEL", "cell_library", "yosys_share"]

#: Families a netlist can be mapped to and simulated for (``--netlist``).
FAMILIES = ("ecp5", "cyclonev")

#: The project's behavioural DP16KD (installed with the package).
DP16KD_MODEL = Path(__file__).with_name("ecp5_dp16kd.v")

_CYCLONEV_FILES = ("alm_sim.v", "dff_sim.v", "mem_sim.v", "dsp_sim.v", "misc_sim.v")


def yosys_share():
    """The ``share`` folder of the ``pyosys`` wheel (its cell libraries)."""
    try:
        import pyosys  # noqa: F401  (sets sys._pyosys_share_dirname)
    except ImportError:
        raise UserError("native Yosys (pyosys) is missing: install it with "
                        "pip install pyosys") from None
    return Path(sys._pyosys_share_dirname)


def _inlined(folder, name, seen):
    """``name`` with its ``include``s replaced by the files, each file once.

    ``cells_sim_ecp5.v`` includes ``cells_ff.vh`` twice (directly and through
    ``common_sim.vh``): a second copy would define its modules twice.
    """
    if name in seen:
        return ""
    seen.add(name)
    text = (folder / name).read_text()
    return re.sub(r'^`include "([^"]+)"', lambda m: _inlined(folder, m.group(1), seen),
                  text, flags=re.M)


def _ecp5():
    text = _inlined(yosys_share() / "lattice", "cells_sim_ecp5.v", set())
    text, count = re.subn(r"^module DP16KD\(.*?^endmodule", "", text, flags=re.S | re.M)
    if count != 1:
        raise RuntimeError("Yosys's cells_sim_ecp5.v no longer has one DP16KD module")
    # An elaboration-time $error in a generate branch for COMB modes the mapping never
    # uses; Icarus rejects $error there.
    text = re.sub(r"\$error\([^;]*\);", "", text)
    return {"cells_ecp5.v": text, "dp16kd.v": DP16KD_MODEL.read_text()}


#: MISTRAL_M10K's array accesses, ``mem[(ADDR + 1) * CFG_DBITS - 1 : ADDR * CFG_DBITS]``:
#: a part select with variable bounds, which Verilog does not allow (Icarus rejects it).
_M10K_SLICE = re.compile(r"mem\[\((\w+) \+ 1\) \* CFG_DBITS - 1 : \1 \* CFG_DBITS\]")


def _cyclonev():
    folder = yosys_share() / "intel_alm" / "common"
    text = "\n".join((folder / name).read_text() for name in _CYCLONEV_FILES)
    # The same bits as an indexed part select.
    text, count = _M10K_SLICE.subn(r"mem[\1 * CFG_DBITS +: CFG_DBITS]", text)
    # The write enable of the 256 x 40 mode: Yosys's map (bram_m10k_map.v) connects it
    # uninverted (the mode was re-enabled by yosys PR #3789) and inverts it for every
    # other width (the M10K's write enable is negative-true, PR #3227); the simulation
    # model inverts it for every width, so a 40-bit M10K would write when not enabled.
    text, fixed = re.subn(r"if \(!A1EN\)", "if (CFG_DBITS == 40 ? A1EN : !A1EN)", text)
    # The read register powers up cleared, as the flip-flops do (dff_sim.v); Yosys's model
    # leaves it X until the first read, and X reaching a register whose enable depends on
    # its own value stays there under a four-state simulator, as no device would.
    text, cleared = re.subn(r"(output reg \[CFG_DBITS-1:0\] B1DATA;)",
                            r"\1\ninitial B1DATA = 0;", text)
    if count != 2 or fixed != 1 or cleared != 1:
        raise RuntimeError("Yosys's MISTRAL_M10K model changed: review cell_models.py")
    return {"cells_cyclonev.v": text}


def cell_library(family):
    """File name -> Verilog text of the cell models for ``family`` (one of
    :data:`FAMILIES`)."""
    if family not in FAMILIES:
        raise UserError(f"--netlist must be one of {', '.join(FAMILIES)}, not {family!r}")
    return _ecp5() if family == "ecp5" else _cyclonev()
