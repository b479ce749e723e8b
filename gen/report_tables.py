"""Text of resource reports: one configuration's table, and the sweep beside the paper."""

from .paper_resources import PAPER_BLOCKS, PAPER_CLOCK, PAPER_DID_NOT_FIT, PAPER_LOGIC, \
    PAPER_MEMORY

__all__ = ["format_table", "sweep_markdown"]


def _number(value, digits=0):
    return "-" if value is None else f"{value:,.{digits}f}"


def _row(target, result):
    if result["status"] != "ok":
        return [target, result["status"], result.get("message", "")]
    return [target, f"{result['logic']:,} {result['logic_unit']}", f"{result['registers']:,}",
            f"{result['block_rams']} {result['block_ram_kind']}", str(result["lut_rams"]),
            f"{result['memory_bits']:,}" + (f" (+{result['ffram_bits']:,} in FFs)"
                                             if result["ffram_bits"] else ""),
            _number(result["fmax_mhz"], 1), _number(result.get("frames_per_second"), 1),
            f"{result['seconds']:.0f}" + (" (cached)" if result.get("cached") else "")]


def format_table(report):
    """Plain-text table of one configuration's results."""
    header = ["target", "logic", "registers", "block RAM", "LUT RAM", "memory bits",
              "Fmax MHz", "frames/s", "seconds"]
    rows = [header] + [_row(t, r) for t, r in report["results"].items()]
    widths = [max(len(row[i]) for row in rows if i < len(row)) for i in range(len(header))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in rows]
    notes = [f"cycles per frame {report['cycles_per_frame']:,}"]
    notes += [f"{t}: {r['message']}" for t, r in report["results"].items()
              if r["status"] == "ok" and r.get("message")]
    notes += [f"{t} critical path: {r['critical_path']}" for t, r in report["results"].items()
              if r.get("critical_path")]
    return "\n".join(lines + notes)


def _cell(result, key):
    if result is None:
        return "not run"
    if result["status"] != "ok":
        return result["status"]
    return _number(result.get(key), 1 if key == "fmax_mhz" else 0)


def _ratio(ours, paper):
    if ours is None or paper is None:
        return "-"
    return f"{ours / paper:.2f}"


def sweep_markdown(reports):
    """Markdown table of the sweep: ours beside the paper, ratios ours / paper."""
    lines = ["| transform | block | Cyclone V ALUTs | paper LEs | ratio | registers | M10K | "
             "memory bits | paper bits | ratio | ECP5 LUT4 | ECP5 Fmax MHz | paper MHz |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for report in reports:
        p = report["params"]
        index = PAPER_BLOCKS.index(p["block"])
        cv = report["results"].get("cyclonev")
        e5 = report["results"].get("ecp5")
        logic = PAPER_LOGIC[p["transform"]][index]
        memory = PAPER_MEMORY[p["transform"]][index]
        ok = cv is not None and cv["status"] == "ok"
        paper_logic = "-" if logic is None else f"{logic:,}" + (
            " (did not fit)" if (p["transform"], p["block"]) in PAPER_DID_NOT_FIT else "")
        lines.append("| " + " | ".join([
            p["transform"], f"{p['block']}x{p['block']}", _cell(cv, "logic"), paper_logic,
            _ratio(cv["logic"], logic) if ok else "-", _cell(cv, "registers"),
            _cell(cv, "block_rams"), _cell(cv, "memory_bits"), f"{memory:,}",
            _ratio(cv["memory_bits"], memory) if ok else "-", _cell(e5, "logic"),
            _cell(e5, "fmax_mhz"), _number(PAPER_CLOCK.get(p["block"]), 0)]) + " |")
    failures = [f"- {r['params']['transform']} {r['params']['block']}x{r['params']['block']} "
                f"{t}: {res['status']}: {res.get('message', '')}"
                for r in reports for t, res in r["results"].items() if res["status"] != "ok"]
    paths = [f"- {r['params']['transform']} {r['params']['block']}x{r['params']['block']}: "
             f"{res['critical_path']}" for r in reports for res in r["results"].values()
             if res.get("critical_path")]
    seconds = [f"- {r['params']['transform']} {r['params']['block']}x{r['params']['block']} "
               f"{t}: {res['seconds']:.0f} s"
               + (f" ({res['yosys_time_split']})" if res.get("yosys_time_split") else "")
               for r in reports
               for t, res in r["results"].items() if "seconds" in res]
    text = "\n".join(lines) + "\n"
    if failures:
        text += "\nFailed or timed out:\n\n" + "\n".join(failures) + "\n"
    if paths:
        text += "\nECP5 critical paths:\n\n" + "\n".join(paths) + "\n"
    return text + "\nSynthesis time per configuration (uncached run):\n\n" + "\n".join(seconds) + "\n"
