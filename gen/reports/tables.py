"""Text of resource reports: one configuration's table, the sweep beside the paper, and the
camera-rate configurations beside the published peers."""

from ...params import StereoParams
from .cache import refused
from .camera import PEERS, evaluations_per_second
from .paper_data import PAPER_BLOCKS, PAPER_CLOCK, PAPER_DID_NOT_FIT, PAPER_LOGIC, \
    PAPER_MEMORY, SAD_TRANSFORMS, is_default_line_buffer

__all__ = ["format_table", "sweep_markdown", "camera_markdown"]


def _number(value, digits=0):
    return "-" if value is None else f"{value:,.{digits}f}"


def _synthesised(result):
    """Whether ``result`` has synthesis figures (also when place and route failed)."""
    return result is not None and result.get("logic") is not None


def _row(target, result):
    if refused(result):  # the verdict before synthesis: only the memory bits are known
        return [target, "-", "-", "-", "-", f"{result['memory_bits']:,}", "-",
                result["message"], "-", "0 (not synthesised)"]
    if not _synthesised(result):
        return [target, result["status"], result.get("message", "")]
    utilisation = result.get("utilisation") or {}
    fmax = {"ok": _number(result["fmax_mhz"], 1), "does not fit": result["message"]}.get(
        result["status"], result["status"])
    return [target, f"{result['logic']:,} {result['logic_unit']}"
            + (f" ({utilisation['LUT']:.0f} % of the LUT sites)" if utilisation else ""),
            f"{result['registers']:,}",
            f"{result['block_rams']} {result['block_ram_kind']}", str(result["lut_rams"]),
            f"{result['memory_bits']:,}" + (f" (+{result['ffram_bits']:,} in FFs)"
                                             if result["ffram_bits"] else ""),
            _number(result.get("logic_levels"), 1), fmax,
            _number(result.get("frames_per_second"), 1),
            f"{result['seconds']:.0f}" + (" (cached)" if result.get("cached") else "")]


def format_table(report):
    """Plain-text table of one configuration's results."""
    header = ["target", "logic", "registers", "block RAM", "LUT RAM", "memory bits",
              "LUT levels", "Fmax MHz", "frames/s", "seconds"]
    rows = [header] + [_row(t, r) for t, r in report["results"].items()]
    widths = [max(len(row[i]) for row in rows if i < len(row)) for i in range(len(header))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in rows]
    notes = [f"cycles per frame {report['cycles_per_frame']:,} (frames back to back)"]
    notes += _lut_notes(report)
    notes += [f"{t}: {r['message']}" for t, r in report["results"].items()
              if r.get("message") and _synthesised(r) and r["status"] != "does not fit"]
    for t, r in report["results"].items():
        path = r.get("logic_levels_path")
        if path:
            notes.append(f"{t} deepest register-to-register logic: {path.get('from')} -> "
                         f"{path.get('to')} ({r['logic_levels']:.1f} LUT levels)")
    notes += [f"{t} critical path: {r['critical_path']}{_router_note(r)}"
              for t, r in report["results"].items() if r.get("critical_path")]
    return "\n".join(lines + notes)


#: The LUT inputs of each target's fabric (what ``lut_inputs`` should say for it).
_TARGET_LUT_INPUTS = {"cyclonev": 6, "ecp5": 4}


def _lut_notes(report):
    """A note per target whose fabric's LUTs the core's sums of absolute differences are
    not arranged for (only ext. rank and ext. census have such sums)."""
    p = report["params"]
    if p["transform"] not in SAD_TRANSFORMS:
        return []
    lut = p.get("lut_inputs", 4)
    return [f"{t}: sums of absolute differences arranged for {lut}-input LUTs; this "
            f"fabric's have {_TARGET_LUT_INPUTS[t]}: --lut-inputs {_TARGET_LUT_INPUTS[t]} "
            f"is smaller here"
            for t in report["results"] if _TARGET_LUT_INPUTS.get(t, lut) != lut]


def _cell(result, key, digits=0):
    """A figure of ``result``, or why there is none (a result refused for its memory has
    its memory bits and no other figure)."""
    if result is None:
        return "not run"
    if result.get(key) is None:
        return result["status"] if result["status"] != "ok" else "-"
    return _number(result.get(key), digits)


def _ratio(ours, paper):
    if ours is None or paper is None:
        return "-"
    return f"{ours / paper:.2f}"


def _levels(result):
    """Logic depth of the worst register-to-register path, in LUT levels."""
    if not _synthesised(result):
        return "-"
    return _number(result.get("logic_levels"), 1)


def _clock(result):
    """ECP5 Fmax, or why there is none."""
    if result is None:
        return "not run", "-"
    if result["status"] == "does not fit":
        return result.get("message", "does not fit"), "-"
    if result["status"] != "ok":
        return result["status"], "-"
    if not result.get("pnr"):
        return "synthesis only", "-"
    return _number(result.get("fmax_mhz"), 1), _number(result.get("frames_per_second"), 1)


def _name(p):
    variants = [p["line_buffer"]] if p.get("line_buffer", "auto") != "auto" else []
    variants += [_LUT6] if p.get("lut_inputs", 4) == 6 else []
    return f"{p['transform']} {p['block']}x{p['block']}" + (
        f" ({', '.join(variants)})" if variants else "")


#: Said of a core whose sums of absolute differences are arranged for 6-input LUTs.
_LUT6 = "6-input LUTs"


def sweep_markdown(reports):
    """Markdown tables of the sweep: ours beside the paper (ratios ours / paper), then the
    ECP5 columns and the clock; one row per transform, block and line buffer."""
    lines = ["| transform | block | rows above | Cyclone V ALUTs | MLABs | paper LEs | ratio "
             "| registers | M10K | memory bits | paper bits | ratio | LUT levels |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    clock = ["| transform | block | rows above | ECP5 LUT4 | FF | DP16KD | LUT sites % "
             "| LUT levels | Fmax MHz | frames/s | paper MHz |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
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
        rows = p.get("line_buffer", "auto")
        if rows != "auto" and is_default_line_buffer(StereoParams(**p)):
            rows += " (default)"
        if p.get("lut_inputs", 4) == 6:
            rows += f", {_LUT6}"
        lines.append("| " + " | ".join([
            p["transform"], f"{p['block']}x{p['block']}", rows, _cell(cv, "logic"),
            _cell(cv, "lut_rams"), paper_logic,
            _ratio(cv["logic"], logic) if ok else "-", _cell(cv, "registers"),
            _cell(cv, "block_rams"), _cell(cv, "memory_bits"), f"{memory:,}",
            _ratio(cv["memory_bits"], memory) if ok else "-", _levels(cv)]) + " |")
        if e5 is None and p.get("lut_inputs", 4) == 6:
            continue    # not for the ECP5's 4-input LUTs (paper_data.sweep_targets)
        fmax, fps = _clock(e5)
        lut = e5.get("utilisation", {}) or {} if e5 else {}
        clock.append("| " + " | ".join([
            p["transform"], f"{p['block']}x{p['block']}", rows, _cell(e5, "logic"),
            _cell(e5, "registers"), _cell(e5, "block_rams"),
            _number(lut.get("LUT"), 0) if lut else "-", _levels(e5), fmax, fps,
            _number(PAPER_CLOCK.get(p["block"]), 0)]) + " |")
    failures = [f"- {_name(r['params'])} {t}: {res['status']}: {res.get('message', '')}"
                for r in reports for t, res in r["results"].items()
                if res["status"] not in ("ok", "does not fit")]
    refusals = [f"- {_name(r['params'])} {t}: {res['message']}" for r in reports
                for t, res in r["results"].items() if refused(res)]
    paths = [f"- {_name(r['params'])}: {res['critical_path']}{_router_note(res)}" for r in reports
             for res in r["results"].values() if res.get("critical_path")]
    seconds = [f"- {_name(r['params'])} {t}: {res['seconds']:.0f} s"
               + (f" ({res['yosys_time_split']})" if res.get("yosys_time_split") else "")
               for r in reports
               for t, res in r["results"].items() if "seconds" in res and not refused(res)]
    text = "\n".join(lines) + "\n\n" + "\n".join(clock) + "\n"
    if failures:
        text += "\nFailed or timed out:\n\n" + "\n".join(failures) + "\n"
    if refusals:
        text += ("\nNot synthesised (the device cannot hold the memories):\n\n"
                 + "\n".join(refusals) + "\n")
    if paths:
        text += "\nECP5 critical paths:\n\n" + "\n".join(paths) + "\n"
    return text + "\nSynthesis time per configuration (uncached run):\n\n" + "\n".join(seconds) + "\n"


def _router_note(result):
    """Said beside a critical path when nextpnr routed without timing-driven rip-up, with a
    placer seed or timing weight or router2's alternate weights given (``--seed``,
    ``--placer-timing-weight``, ``--router-alt-weights``), or with
    the clock on a pin the flow chose
    (:data:`~npstereo.gen.flow.nextpnr.CLOCK_PIN`)."""
    notes = [result.get("ripup_abandoned")]
    if result.get("seed") is not None:
        notes.append(f"placer seed {result['seed']}")
    if result.get("placer_timing_weight") is not None:
        notes.append(f"placer timing weight {result['placer_timing_weight']}")
    if result.get("router_alt_weights"):
        notes.append("router2's alternate weights")
    if result.get("clock_pin"):
        notes.append(f"clock on pin {result['clock_pin']}: the placer's pad could not "
                     "reach the clock network")
    notes = [note for note in notes if note]
    return f" ({'; '.join(notes)})" if notes else ""


def camera_markdown(reports):
    """The camera table: one row per configuration (ECP5 and Cyclone V columns), then the
    peers, then what did not fit or failed."""
    lines = ["| matcher | frame | D | R | ECP5 LUT4 | LUT sites % | FF | DP16KD | Fmax MHz "
             "| frames/s | G evaluations/s | Cyclone V ALUTs | M10K |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    notes = []
    for report in reports:
        p = StereoParams(**report["params"])
        e5, cv = report["results"].get("ecp5"), report["results"].get("cyclonev")
        fmax, fps = _clock(e5)
        rate = "-"
        if e5 is not None and e5.get("frames_per_second"):
            rate = _number(evaluations_per_second(p.width, p.height, p.disparities,
                                                  e5["frames_per_second"]) / 1e9, 2)
        lut = (e5 or {}).get("utilisation") or {}
        matcher = f"{p.transform} {p.block}x{p.block} " + ("SGM" if p.is_sgm else
                                                            f"{p.aggregation}x{p.aggregation} box")
        lines.append("| " + " | ".join([
            matcher, f"{p.width}x{p.height}", str(p.disparities), str(p.rounds),
            _cell(e5, "logic"), _number(lut.get("LUT")) if lut else "-",
            _cell(e5, "registers"), _cell(e5, "block_rams"), fmax, fps, rate,
            _cell(cv, "logic"), _cell(cv, "block_rams")]) + " |")
        for target, result in report["results"].items():
            if result["status"] != "ok":    # a memory refusal is "does not fit" too
                notes.append(f"- {p.describe()} {target}: {result['status']}: "
                             f"{result.get('message', '')}")
    peers = ["| design | frame | D | frames/s | G evaluations/s |", "|---|---|---:|---:|---:|"]
    peers += [f"| {name} | {w}x{h} | {d} | {fps:.0f} | "
              f"{evaluations_per_second(w, h, d, fps) / 1e9:.1f} |"
              for name, w, h, d, fps in PEERS]
    text = "\n".join(lines) + "\n\nPublished peers:\n\n" + "\n".join(peers) + "\n"
    if notes:
        text += "\nNot fitting, failed or not run to the end:\n\n" + "\n".join(notes) + "\n"
    return text
