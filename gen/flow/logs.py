"""Figures read from what Yosys and nextpnr write: cell counts, memory bits, carry chains,
where Yosys spent its time, nextpnr's clock and critical path."""

import json
from pathlib import Path

__all__ = ["memory_cells_bits", "cell_counts", "target_resources", "carry_chains",
           "time_split", "nextpnr_timing"]


def memory_cells_bits(path):
    """Bits held by the ``$mem_v2`` cells of a ``write_json`` file (WIDTH x SIZE each)."""
    bits = count = 0
    for module in json.loads(Path(path).read_text())["modules"].values():
        for cell in module.get("cells", {}).values():
            if cell["type"] == "$mem_v2":
                parameters = cell["parameters"]
                bits += int(parameters["WIDTH"], 2) * int(parameters["SIZE"], 2)
                count += 1
    return bits, count


def cell_counts(path):
    """Cells by type of a ``stat -json`` file."""
    design = json.loads(Path(path).read_text())["design"]
    return dict(design.get("num_cells_by_type", {}))


def target_resources(target, cells):
    """Target-specific cell counts, named the same for both targets where possible."""
    def total(prefix):
        return sum(n for name, n in cells.items() if name.startswith(prefix))
    if target == "cyclonev":
        return {"logic": total("MISTRAL_ALUT"), "logic_unit": "ALUT",
                "registers": total("MISTRAL_FF"), "block_rams": total("MISTRAL_M10K"),
                "block_ram_kind": "M10K", "lut_rams": total("MISTRAL_MLAB"),
                "dsps": total("MISTRAL_MUL")}
    return {"logic": total("LUT4") + 2 * total("CCU2C"), "logic_unit": "LUT4",
            "registers": total("TRELLIS_FF"), "block_rams": total("DP16KD"),
            "block_ram_kind": "DP16KD", "lut_rams": total("TRELLIS_DPR16X4"),
            "dsps": total("MULT18X18D")}


def carry_chains(netlist):
    """CCU2C carry chains in a Yosys JSON netlist (parsed) of the ECP5: the cells whose
    carry-in no other CCU2C drives. nextpnr-ecp5 packs two more CCU2C cells into every
    chain (one to feed its carry in, one to bring its carry out), which :mod:`.capacity`
    counts."""
    carries = [cell["connections"] for module in netlist["modules"].values()
               for cell in module.get("cells", {}).values() if cell["type"] == "CCU2C"]
    driven = {tuple(ports["COUT"]) for ports in carries}
    return sum(tuple(ports["CIN"]) not in driven for ports in carries)


def time_split(log_path):
    """Yosys's closing ``Time spent: ...`` line: which passes took the time."""
    lines = [line for line in Path(log_path).read_text(errors="replace").splitlines()
             if line.startswith("Time spent:")]
    return lines[-1][len("Time spent:"):].strip() if lines else ""


def nextpnr_timing(report_path):
    """Lowest achieved clock (MHz) of a nextpnr ``--report`` file and its critical path.

    The path is summarised as start cell -> end cell with its delay and logic levels, which
    is what the HDL authors need to know where to add a register.
    """
    report = json.loads(Path(report_path).read_text())
    achieved = [clock["achieved"] for clock in report.get("fmax", {}).values()]
    path = ""
    for critical in report.get("critical_paths", []):
        # Only register-to-register paths limit the clock; I/O paths are unconstrained.
        if critical["from"].startswith("posedge") and critical["to"].startswith("posedge"):
            steps = critical["path"]
            delay = sum(step["delay"] for step in steps)
            levels = sum(step["type"] == "logic" for step in steps)
            path = (f"{steps[0]['from']['cell']} -> {steps[-1]['to']['cell']}: "
                    f"{delay:.2f} ns, {levels} logic levels")
            break
    return (min(achieved) if achieved else None), path
