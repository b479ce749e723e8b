"""``npstereo board``: the board top simulated against the golden model (a reduced frame
under Amaranth's simulator; the full 640x480 frame under Verilator is in
tests/bench_board.py), the TMDS encoder against the DVI specification's decoding, and
the inputs the command refuses.
"""

import json
import random

import numpy as np
import pytest
from amaranth.sim import Simulator
from PIL import Image

from npstereo.gen.board.display import DepthDisplay
from npstereo.gen.board.fit import BOARDS, display_blocks, largest_pair
from npstereo.gen.board.tmds import CONTROL_SYMBOLS, TMDSEncoder
from npstereo.gen.board.verify import capture_amaranth, compare
from npstereo.gen.board.video import VideoTiming, colour_table, expected_frame
from npstereo.gen.cli.main import main
from npstereo.golden.pipeline import disparity_map
from npstereo.golden.synthetic import synthetic_pair
from npstereo.params import StereoParams

#: A reduced video mode: the 32 x 12 map doubled (64 x 24) and centred in 72 x 28, with
#: black around it; 2,560 clocks a frame.
SMALL_TIMING = VideoTiming(72, 2, 4, 2, 28, 1, 2, 1)


@pytest.fixture(scope="module")
def small_board():
    pair = synthetic_pair(width=32, height=12, disparities=8, seed=1)
    left, right = pair.gray()
    params = StereoParams(transform="census", block=5, disparities=8, rounds=2,
                          width=32, height=12)
    golden = disparity_map(left, right, params).disparity
    assert (golden >= 0).any() and (golden < 0).any()
    return params, left, right, expected_frame(golden, 8, SMALL_TIMING)


def test_board_top_frame_is_bit_exact(small_board):
    """The pixels the display receives, one whole frame after the first map, are the
    golden model's colour-mapped, scaled and centred map; the frame has the mode's length
    and line count."""
    params, left, right, expected = small_board
    capture = capture_amaranth(DepthDisplay(params, left, right, SMALL_TIMING), SMALL_TIMING)
    check = compare(expected, capture, SMALL_TIMING)
    assert check.ok, check.message()


def test_board_top_with_an_off_by_one_colour_map_fails(small_board):
    """Broken variant: the colour ROM shifted by one disparity."""
    params, left, right, expected = small_board
    shifted = np.roll(colour_table(params.disparities), 1, axis=0)
    capture = capture_amaranth(DepthDisplay(params, left, right, SMALL_TIMING, shifted),
                               SMALL_TIMING)
    check = compare(expected, capture, SMALL_TIMING)
    assert not check.ok and check.mismatches > 0, check.message()


@pytest.fixture(scope="module")
def fraction_board():
    """The small board with the 3x3 median and F = 3 fractional bits: the frame buffer
    holds the values, the colour ROM has one entry for each of 0 .. (D - 1) 2^3."""
    pair = synthetic_pair(width=32, height=12, disparities=8, seed=1)
    left, right = pair.gray()
    params = StereoParams(transform="census", block=5, disparities=8, rounds=2,
                          width=32, height=12, median=True, subpixel_bits=3)
    golden = disparity_map(left, right, params).disparity
    assert ((golden >= 0) & (golden % 8 != 0)).any() and (golden < 0).any()
    return params, left, right, expected_frame(golden, 8, SMALL_TIMING, bits=3)


def test_board_top_with_median_and_fraction_is_bit_exact(fraction_board):
    params, left, right, expected = fraction_board
    assert len(colour_table(8, 3)) == 7 * 8 + 1
    # A whole level keeps its F = 0 colour.
    assert np.array_equal(colour_table(8, 3)[::8], colour_table(8))
    capture = capture_amaranth(DepthDisplay(params, left, right, SMALL_TIMING), SMALL_TIMING)
    check = compare(expected, capture, SMALL_TIMING)
    assert check.ok, check.message()


def test_board_top_with_the_fraction_off_by_one_step_fails(fraction_board):
    """Broken variant: the colour ROM shifted by one step of 1/8 level (the fraction's
    last bit shows on the screen)."""
    params, left, right, expected = fraction_board
    shifted = np.roll(colour_table(8, 3), 1, axis=0)
    capture = capture_amaranth(DepthDisplay(params, left, right, SMALL_TIMING, shifted),
                               SMALL_TIMING)
    check = compare(expected, capture, SMALL_TIMING)
    assert not check.ok and check.mismatches > 0, check.message()


def _decode(symbol):
    """DVI 1.0's decoder (section 3.3.4): the data byte of a data symbol."""
    low = symbol & 0xFF
    if symbol & 0x200:
        low ^= 0xFF
    data = low & 1
    for i in range(1, 8):
        bit = ((low >> i) ^ (low >> (i - 1))) & 1
        data |= (bit if symbol & 0x100 else bit ^ 1) << i
    return data


def _encode(encoder, beats):
    symbols = []

    async def bench(ctx):
        for data, de, c0, c1 in beats:
            ctx.set(encoder.data, data)
            ctx.set(encoder.de, de)
            ctx.set(encoder.c0, c0)
            ctx.set(encoder.c1, c1)
            await ctx.tick()
            symbols.append(ctx.get(encoder.symbol))
        for _ in range(2):
            await ctx.tick()
            symbols.append(ctx.get(encoder.symbol))

    sim = Simulator(encoder)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    # The symbol of a beat is registered at the second clock edge after it is set: it is
    # read after the next beat's edge.
    return symbols[1:len(beats) + 1]


def _tmds_problems(beats, symbols, bound=12):
    """What the symbols get wrong: a data symbol that decodes to another byte, a wrong
    control symbol, or a running disparity (ones minus zeros sent) beyond ``bound``."""
    problems, running = [], 0
    for (data, de, c0, c1), symbol in zip(beats, symbols):
        if not de:
            running = 0
            if symbol != CONTROL_SYMBOLS[c1 * 2 + c0]:
                problems.append(f"control ({c1}, {c0}): {symbol:010b}")
            continue
        if _decode(symbol) != data:
            problems.append(f"{data:#04x} sent as {symbol:010b}")
        running += 2 * bin(symbol).count("1") - 10
        if abs(running) > bound:
            problems.append(f"running disparity {running}")
    return problems


def _beats():
    """Lines of 200 data bytes (uniform, then mostly ones or zeros) between blanking
    with every control pair."""
    rng = random.Random(3)
    beats = []
    for line, pick in enumerate((lambda: rng.randrange(256), lambda: rng.choice((0xFF, 0xFE, 0xF7)),
                                 lambda: rng.choice((0, 1, 0x10)))):
        beats += [(0, 0, line & 1, line >> 1)] * 4
        beats += [(pick(), 1, 0, 0) for _ in range(200)]
    return beats + [(0, 0, 1, 1)] * 4


def test_tmds_encoder_decodes_and_stays_balanced():
    """Every data byte comes back through DVI's decoder, blanking sends the control
    symbols and the running disparity stays small; broken variants: the same symbols
    never sent inverted (no DC balance), and one bit flipped."""
    beats = _beats()
    symbols = _encode(TMDSEncoder(), beats)
    assert _tmds_problems(beats, symbols) == []
    unbalanced = [symbol ^ 0x2FF if symbol & 0x200 and de else symbol
                  for symbol, (_, de, _, _) in zip(symbols, beats)]
    assert any("running disparity" in p for p in _tmds_problems(beats, unbalanced))
    flipped = list(symbols)
    flipped[10] ^= 1 << 3
    assert _tmds_problems(beats, flipped)


def _refused(capsys, argv, *words):
    """``npstereo argv`` is one line naming ``words``, exit code 2, no traceback."""
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("npstereo: error: "), captured.err
    assert all(word in lines[0] for word in words), lines[0]
    assert "Traceback" not in captured.err + captured.out
    return lines[0]


def _pair_files(folder, width, height):
    rng = np.random.default_rng(0)
    paths = []
    for side in ("left", "right"):
        path = folder / f"{side}.png"
        Image.fromarray(rng.integers(0, 256, (height, width), np.uint8)).save(path)
        paths.append(str(path))
    return paths


def test_unknown_board_is_refused(tmp_path, capsys):
    _refused(capsys, ["board", "de10-nano", "--out", str(tmp_path / "out")],
             "de10-nano", "ulx3s-85f")
    assert not (tmp_path / "out").exists()


def test_a_pair_too_large_for_the_block_ram_is_refused(tmp_path, capsys):
    """640 x 480 fits the screen, not the block RAM: the message says how large a pair
    may be, and nothing is written."""
    left, right = _pair_files(tmp_path, 640, 480)
    params = StereoParams(transform="census", block=9, disparities=32, rounds=4,
                          width=640, height=480)
    most = largest_pair(BOARDS["ulx3s-85f"], params)
    assert 160 * 120 <= most < 640 * 480
    line = _refused(capsys, ["board", "ulx3s-85f", "--left", left, "--right", right,
                             "--out", str(tmp_path / "out")], "640x480", "DP16KD", "208")
    assert f"at most {most:,} pixels" in line
    assert not (tmp_path / "out").exists()


def test_a_pair_wider_than_the_screen_is_refused(tmp_path, capsys):
    left, right = _pair_files(tmp_path, 700, 40)
    _refused(capsys, ["board", "ulx3s-85f", "--left", left, "--right", right,
                      "--out", str(tmp_path / "out")], "700x40", "640x480 screen")


def test_out_into_a_file_and_half_a_pair_are_refused(tmp_path, capsys):
    a_file = tmp_path / "a-file"
    a_file.write_text("x")
    _refused(capsys, ["board", "ulx3s-85f", "--out", str(a_file)], "--out", str(a_file),
             "not a folder")
    left, _ = _pair_files(tmp_path, 64, 40)
    _refused(capsys, ["board", "ulx3s-85f", "--left", left, "--out", str(tmp_path / "o")],
             "--left and --right")
    assert a_file.read_text() == "x" and not (tmp_path / "o").exists()


def test_ulx3s_top_drives_the_gpdi_pins_through_the_pll_and_ddr_registers(small_board):
    """amaranth-boards' ULX3S platform: the three TMDS data pairs and the clock pair on the
    GPDI pins as LVCMOS33D, each through an ODDRX1F, the clocks from one EHXPLLL fed by
    the 25 MHz oscillator (G2), whose constraint nextpnr carries through the PLL."""
    from amaranth_boards.ulx3s import ULX3S_85F_Platform

    from npstereo.gen.board.ulx3s import ULX3STop
    params, left, right, _ = small_board
    plan = ULX3S_85F_Platform().prepare(
        ULX3STop(DepthDisplay(params, left, right, SMALL_TIMING)), name="top")
    lpf, rtlil = plan.files["top.lpf"], plan.files["top.il"]
    for port, site in (("hdmi_0__d__p[0]", "A16"), ("hdmi_0__d__p[1]", "A14"),
                       ("hdmi_0__d__p[2]", "A12"), ("hdmi_0__clk__p", "A17")):
        assert f'LOCATE COMP "{port}" SITE "{site}";' in lpf
        assert f'IOBUF PORT "{port}" IO_TYPE=LVCMOS33D' in lpf
    assert 'LOCATE COMP "clk25_0__io" SITE "G2";' in lpf
    assert 'FREQUENCY PORT "clk25_0__io" 25000000.0 HZ;' in lpf
    assert rtlil.count("cell \\ODDRX1F") == 4 and rtlil.count("cell \\EHXPLLL") == 1


def test_a_path_between_the_clocks_is_held_to_the_faster_period(tmp_path):
    """nextpnr checks each clock against its own constraint; the path from the pixel
    clock to the serialiser's is held here to 8 ns (125 MHz). Broken variant: the same
    report with that path at 9 ns is over its budget."""
    from npstereo.gen.board.flow import clock_report

    def report(delay):
        path = tmp_path / f"report-{delay}.json"
        path.write_text(json.dumps({
            "fmax": {"pixel": {"achieved": 77.6, "constraint": 25.0},
                     "shift": {"achieved": 272.5, "constraint": 125.0}},
            "critical_paths": [
                {"from": "posedge pixel", "to": "posedge pixel", "path": [{"delay": 12.0}]},
                {"from": "posedge pixel", "to": "<async>", "path": [{"delay": 7.0}]},
                {"from": "posedge pixel", "to": "posedge shift",
                 "path": [{"delay": delay / 2}, {"delay": delay / 2}]}]}))
        return clock_report(path)

    clocks, crossings = report(1.7)
    assert clocks == [("pixel", 77.6, 25.0), ("shift", 272.5, 125.0)]
    assert crossings == [("pixel", "shift", 1.7, 8.0)]
    (_, _, delay, budget), = report(9.0)[1]
    assert delay > budget


@pytest.mark.parametrize("bits", ["6", "-1"])
def test_subpixel_bits_out_of_range_is_refused(bits, tmp_path, capsys):
    assert main(["board", "ulx3s-85f", "--subpixel-bits", bits,
                 "--out", str(tmp_path / "out")]) == 2
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [
        f"npstereo: error: subpixel bits must be an integer 0 .. 5, not {bits}"]
    assert "Traceback" not in captured.err + captured.out
    assert not (tmp_path / "out").exists()


def test_the_fraction_counts_in_the_block_ram():
    """The frame buffer's F more bits and the colour ROM of (D - 1) 2^F + 1 entries."""
    params = StereoParams(transform="census", block=9, disparities=32, rounds=4,
                          width=160, height=120)
    board = BOARDS["ulx3s-85f"]
    whole, fine = largest_pair(board, params), largest_pair(board, params.replace(
        subpixel_bits=5))
    assert display_blocks(160 * 120, params.replace(subpixel_bits=5)) > display_blocks(
        160 * 120, params) and fine < whole
