"""The fifth SGM path (right to left along the row, ``fifth_path``) in the golden model, its
parameter and its command-line flag (the hardware: tests/test_hdl_sgm_right.py).

docs/semantics.md, "The fifth path": the left path of the mirrored row. The reference here
is tests/test_sgm.py's plain left-path row (Python loops and integers, written from
semantics.md) run on each row read right to left, with P2 from the neighbour on the right
computed pixel by pixel; it shares no code with golden/sgm.py. Every ``test_broken_*`` case
breaks one rule of the golden model and asserts that the comparison now fails.
"""

import json

import numpy as np
import pytest

from npstereo.gen.cli.main import main
from npstereo.gen.flow.block_rams import core_block_rams
from npstereo.gen.flow.capacity import memory_fit_message, target_device
from npstereo.golden import sgm
from npstereo.golden.pipeline import disparity_map as pipeline_map
from npstereo.golden.subpixel import fit_volume, with_fraction
from npstereo.hdl.plan_memories import memory_bits
from npstereo.params import (SGM_PATHS, ParameterError, StereoParams, max_path_penalty,
                             sgm_left_cost_bits, sgm_summed_cost_bits)

import reference
from test_cli_sgm import D as CLI_D, assert_exact_user_error, command_line, run_match
from test_sgm import (REF_K, as_array, left_volume, make_pair, ref_costs, ref_left_row,
                      ref_p2, ref_summed)


def ref_right(costs, p1, p2, image=None, adapt=None):
    """L_right[y][x][d]: each row read right to left through the plain left-path row, P2 at
    x from |I(x) - I(x + 1)|, the result read back left to right."""
    out = []
    for y, row in enumerate(costs):
        width = len(row)
        # Position x' = W - 1 - x of the mirrored row; its predecessor x' - 1 is x + 1.
        penalties = [ref_p2(image, width - 1 - i, y, width - i, y, p1, p2, adapt) if i else p2
                     for i in range(width)]
        out.append(ref_left_row(row[::-1], p1, penalties)[::-1])
    return out


def ref_five(costs, p1, p2, image=None, adapt=None):
    four = ref_summed(costs, SGM_PATHS, p1, p2, image, adapt)
    right = ref_right(costs, p1, p2, image, adapt)
    return [[[a + b for a, b in zip(cell, extra)] for cell, extra in zip(row, other)]
            for row, other in zip(four, right)]


def ref_map_five(left, right, name, block, disparities, p1, p2, adapt, threshold):
    costs = ref_costs(left, right, name, block, disparities)
    return reference.disparity_from_aggregated(ref_five(costs, p1, p2, left, adapt), 1,
                                               threshold)


def golden_right(costs, p1, p2, image=None, adapt=None, max_cost=None):
    return sgm.right_path_costs(np.asarray(costs, np.uint32), p1, p2, image, adapt,
                                max_cost).astype(np.int64)


# The path alone ----------------------------------------------------------------------------

#: (height, width, D, Cmax, P1, P2, kind): rows longer than K so that the tracked disparity
#: comes from K positions to the right; ties (levels), extremes, one disparity.
RIGHT_CASES = [(3, 40, 5, 24, 16, 96, "random"), (2, 37, 6, 3, 1, 5, "levels"),
               (2, 35, 4, 48, 24, 79, "extreme"), (2, 20, 1, 8, 2, 9, "random"),
               (1, 1, 3, 8, 2, 9, "random")]


@pytest.mark.parametrize("height, width, D, cmax, p1, p2, kind", RIGHT_CASES)
@pytest.mark.parametrize("adapt", [None, 2, 5])
def test_right_path_matches_reference(height, width, D, cmax, p1, p2, kind, adapt):
    rng = np.random.default_rng(width + D)
    costs = left_volume(rng, height, width, D, cmax, kind)
    image = rng.integers(0, 256, (height, width)).astype(np.uint8)
    expected = as_array(ref_right(costs.tolist(), p1, p2, image, adapt))
    got = golden_right(costs, p1, p2, image if adapt else None, adapt, cmax)
    assert np.array_equal(got, expected)
    # Counterpart: it is not the left path (the comparison can tell directions apart).
    left = sgm.path_costs(costs, "left", p1, p2, image if adapt else None, adapt, cmax)
    # (With one disparity or one column every path is L = C.)
    assert width == 1 or D == 1 or not np.array_equal(left.astype(np.int64), expected)


def test_right_path_starts_fresh_at_the_last_column():
    costs = np.random.default_rng(3).integers(0, 25, (2, 30, 4))
    got = golden_right(costs, 16, 96, max_cost=24)
    assert np.array_equal(got[:, -1], costs[:, -1])
    assert not np.array_equal(got[:, 0], costs[:, 0])


def test_right_path_p2_uses_the_neighbour_on_the_right():
    # A single step of 200 between x = 4 and x = 5: only x = 4 sees it from the right
    # (bitlen(200) - 5 = 3: max(P1, 79 >> 3) = 10).
    image = np.zeros((1, 8), np.uint8)
    image[0, 5:] = 200
    p2 = sgm.right_path_p2(image, 10, 79, adapt=5)
    assert p2[0].tolist() == [79, 79, 79, 79, 10, 79, 79, 79]


@pytest.mark.parametrize("cmax", [1, 24, 48, 6120])
def test_right_path_widths_hold(cmax):
    """Costs only 0 and Cmax at the largest P2: equal to the unbounded reference, within
    K Cmax + P2, and S of five paths within its width."""
    p2 = max_path_penalty(cmax)
    p1 = p2 // 3
    rng = np.random.default_rng(cmax)
    costs = rng.choice([0, cmax], (4, 40, 5))
    image = rng.choice([0, 255], (4, 40)).astype(np.uint8)
    expected = as_array(ref_right(costs.tolist(), p1, p2, image, 1))
    assert np.array_equal(golden_right(costs, p1, p2, image, 1, cmax), expected)
    assert 0 <= expected.min() and expected.max() <= REF_K * cmax + p2
    assert expected.max() < 2 ** sgm_left_cost_bits(cmax, p2)
    summed = sgm.aggregate(costs, p1, p2, guide=image, adapt=1, max_cost=cmax,
                           fifth_path=True)
    assert np.array_equal(summed.astype(np.int64),
                          as_array(ref_five(costs.tolist(), p1, p2, image, 1)))
    assert summed.max() < 2 ** sgm_summed_cost_bits(cmax, p2, fifth_path=True)


def test_summed_width_formulae():
    # Defaults: 2 x (32 x 48 + 79) + 3 x 127 = 3,611 (12 bits, four paths 11); census 5x5
    # 16/96: 2 x 864 + 3 x 120 = 2,088 (12 bits, four paths 11).
    assert sgm_summed_cost_bits(48, 79, fifth_path=True) == 12
    assert sgm_summed_cost_bits(24, 96, fifth_path=True) == 12
    five = StereoParams(transform="census", block=7, aggregation="sgm", fifth_path=True)
    assert (five.aggregated_cost_bits, five.replace(fifth_path=False).aggregated_cost_bits) \
        == (12, 11)


# Whole maps ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name, block, D, kind, p1, p2, adapt, threshold", [
    ("census", 3, 6, "random", 2, 9, None, 1),
    ("census", 5, 5, "levels", 8, 40, 4, 3),
    ("rank", 3, 4, "ramp", 1, 20, 3, 0),
    ("ext-census", 3, 4, "saturated", 300, 1700, 2, None),
])
def test_disparity_map_with_the_fifth_path_matches_reference(name, block, D, kind, p1, p2,
                                                             adapt, threshold):
    left, right = make_pair(kind, 5, 22, seed=block + D)
    params = StereoParams(transform=name, block=block, disparities=D, lr_threshold=threshold,
                          aggregation="sgm", p1=p1, p2=p2, p2_adapt=adapt or 0,
                          fifth_path=True)
    expected = as_array(ref_map_five(left, right, name, block, D, p1, p2, adapt, threshold))
    got = sgm.disparity_map(left, right, params, p1, p2, adapt=adapt)
    assert np.array_equal(got.disparity, expected)
    # The pipeline takes the option from the parameters; without it the map differs.
    assert np.array_equal(pipeline_map(left, right, params).disparity, expected)
    four = sgm.disparity_map(left, right, params.replace(fifth_path=False), p1, p2,
                             adapt=adapt)
    assert not np.array_equal(four.disparity, expected)


def test_fifth_path_band_seams(monkeypatch):
    left, right = make_pair("random", 9, 30, seed=4)
    params = StereoParams(transform="census", block=5, disparities=8, aggregation="sgm",
                          fifth_path=True)
    whole = sgm.disparity_map(left, right, params, 16, 96, adapt=4)
    monkeypatch.setattr(sgm, "_BAND_ELEMENTS", 2 * 30 * 8)  # bands of two rows
    banded = sgm.disparity_map(left, right, params, 16, 96, adapt=4)
    assert np.array_equal(banded.disparity, whole.disparity)
    assert np.array_equal(banded.right, whole.right)


def test_fifth_path_with_subpixel_fits_the_five_path_sums():
    left, right = make_pair("random", 4, 24, seed=2)
    params = StereoParams(transform="census", block=5, disparities=6, aggregation="sgm",
                          p1=16, p2=96, p2_adapt=4, fifth_path=True, subpixel_bits=3)
    got = sgm.disparity_map(left, right, params, 16, 96, adapt=4)
    volume = sgm.cost_volume(left, right, params)
    summed = sgm.aggregate(volume, 16, 96, guide=left, adapt=4, max_cost=params.max_cost,
                           fifth_path=True)
    raw_left, _ = sgm.winners(summed)
    expected = fit_volume(summed, raw_left, 3)
    fitted = with_fraction(sgm.disparity_from_summed(summed, 3), expected, 3)
    assert np.array_equal(got.disparity, fitted.disparity)


# Broken variants ---------------------------------------------------------------------------


def right_case_differs():
    """Whether the golden fifth path differs from the reference on a few adaptive cases."""
    for height, width, D, cmax, p1, p2, kind in RIGHT_CASES[:3]:
        rng = np.random.default_rng(width + D)
        costs = left_volume(rng, height, width, D, cmax, kind)
        image = rng.integers(0, 256, (height, width)).astype(np.uint8)
        expected = as_array(ref_right(costs.tolist(), p1, p2, image, 2))
        if not np.array_equal(golden_right(costs, p1, p2, image, 2, cmax), expected):
            return True
    return False


def test_broken_baseline_matches():
    assert not right_case_differs()


def test_broken_p2_from_the_left_neighbour_is_caught(monkeypatch):
    # disparity_map's fifth path with the left path's P2 (|I(x) - I(x - 1)|).
    monkeypatch.setattr(sgm, "right_path_p2", lambda guide, p1, p2, adapt=None:
                        sgm.path_p2(guide, "left", p1, p2, adapt))
    with pytest.raises(AssertionError):
        test_disparity_map_with_the_fifth_path_matches_reference(
            "census", 5, 5, "levels", 8, 40, 4, 3)


def test_broken_unmirrored_guide_is_caught(monkeypatch):
    # right_path_costs with the guide left in image order (P2 of the wrong pixels).
    real = sgm.path_costs

    def unmirrored_guide(volume, path, p1, p2, guide=None, adapt=None, max_cost=None):
        guide = None if guide is None else np.asarray(guide)[:, ::-1]
        return real(volume, path, p1, p2, guide, adapt, max_cost)
    monkeypatch.setattr(sgm, "path_costs", unmirrored_guide)
    assert right_case_differs()


def test_broken_unmirrored_path_is_caught(monkeypatch):
    # The left path summed a second time instead of the mirrored one.
    real = sgm.path_costs
    monkeypatch.setattr(sgm, "right_path_costs",
                        lambda volume, p1, p2, guide=None, adapt=None, max_cost=None:
                        real(volume, "left", p1, p2, guide, adapt, max_cost))
    assert right_case_differs()


def test_broken_band_path_is_caught(monkeypatch):
    # disparity_map's banded fifth path as the left path: the whole-map comparison fails.
    monkeypatch.setattr(sgm, "_right_band", lambda costs, p1, p2, out:
                        sgm._left_band(costs, p1, p2, out))
    with pytest.raises(AssertionError):
        test_disparity_map_with_the_fifth_path_matches_reference(
            "census", 5, 5, "levels", 8, 40, 4, 3)


# Parameters and command line --------------------------------------------------------------


def test_parameter_errors_and_repr():
    with pytest.raises(ParameterError) as error:
        StereoParams(fifth_path=True)
    assert str(error.value) == ("the fifth path is an SGM path: it needs aggregation 'sgm', "
                                "not a 3x3 box")
    with pytest.raises(ParameterError) as error:
        StereoParams(aggregation="sgm", fifth_path=1)
    assert str(error.value) == "fifth path must be True or False, not 1"
    four = StereoParams(aggregation="sgm")
    five = four.replace(fifth_path=True)
    # Off, the report cache's key is unchanged; on, it differs and describe() says so.
    assert "fifth_path" not in repr(four) and "fifth_path=True" in repr(five)
    assert five.describe_aggregation() == "SGM P1=24 P2=79 t=5 5 paths"


def test_match_and_eval_take_the_fifth_path(capsys, tmp_path, pair_files, small_pair):
    got = run_match(tmp_path, pair_files, "five", "--block", "5", "--aggregation", "sgm",
                    "--p1", "10", "--p2", "60", "--fifth-path")
    gray = small_pair.gray()
    params = StereoParams(transform="census", block=5, disparities=CLI_D, aggregation="sgm",
                          p1=10, p2=60, fifth_path=True)
    expected = sgm.disparity_map(*gray, params, 10, 60, adapt=5).disparity
    assert np.array_equal(got, expected)
    assert "SGM P1=10 P2=60 t=5 5 paths" in capsys.readouterr().out
    assert not np.array_equal(got, sgm.disparity_map(
        *gray, params.replace(fifth_path=False), 10, 60, adapt=5).disparity)
    _, _, scene = pair_files
    result = tmp_path / "grid.json"
    assert main(["eval", "--dataset", str(scene), "--block", "5", "--aggregation", "3", "sgm",
                 "--fifth-path", "--disparities", str(CLI_D), "--json", str(result)]) == 0
    rows = json.loads(result.read_text())
    assert [(r["aggregation"], r["fifth_path"]) for r in rows] == [(3, False), ("sgm", True)]


@pytest.mark.parametrize("command", ["match", "eval", "verilog", "cosim", "report"])
def test_fifth_path_needs_sgm(capsys, tmp_path, pair_files, command):
    argv = command_line(command, tmp_path, pair_files) + ["--fifth-path"]
    assert_exact_user_error(capsys, tmp_path, argv,
                            "--fifth-path is an SGM option: it needs --aggregation sgm")


def test_prove_needs_sgm_for_the_fifth_path(capsys, tmp_path):
    """``prove`` proves the fifth path (tests/test_prove.py), and refuses it without SGM."""
    argv = ["prove", "--out", str(tmp_path / "o" / "prove"), "--block", "3", "--fifth-path"]
    assert_exact_user_error(capsys, tmp_path, argv,
                            "--fifth-path is an SGM option: it needs --aggregation sgm")


def test_hardware_commands_build_the_fifth_path(capsys, tmp_path, pair_files):
    """The Verilog says so, and Amaranth's simulator gives the golden five-path map on a
    crop of the pair at R = 1."""
    options = ["--aggregation", "sgm", "--rounds", "8", "--p1", "16", "--p2", "90",
               "--fifth-path"]
    assert main(command_line("verilog", tmp_path, pair_files) + options) == 0
    head = (tmp_path / "o" / "c.v").read_text()[:1000]
    assert "aggregation=sgm p1=16 p2=90 p2_adapt=5 fifth_path" in head
    _, _, scene = pair_files
    assert main(["cosim", "--simulator", "amaranth", "--dataset", str(scene), "--crop", "24x6",
                 "--out", str(tmp_path / "cosim"), "--block", "3", "--disparities", str(CLI_D),
                 "--aggregation", "sgm", "--rounds", "1", "--p1", "4", "--p2", "40",
                 "--fifth-path"]) == 0
    assert "mismatches:       0 (bit-exact)" in capsys.readouterr().out


def test_report_counts_the_fifth_paths_memory(capsys, tmp_path):
    """Its rows are counted before any synthesis: census 5x5 SGM at 1920 x 1080, D = 64,
    R = 4 holds 2.75 Mbit of the ECP5-85k's 4.5 without the fifth path, 4.8 with it; as
    Yosys maps them, 156 of its 208 DP16KD without, 270 with it (130 %, the verdict
    shown)."""
    argv = ["report", "--transform", "census", "--block", "5", "--disparities", "64",
            "--rounds", "4", "--aggregation", "sgm", "--p1", "16", "--p2", "96",
            "--p2-adapt", "4", "--width", "1920", "--height", "1080", "--target", "ecp5",
            "--no-cache", "--fifth-path"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "5 paths" in captured.err and "does not fit (memory 130 %)" in captured.out
    assert "4,799,402" in captured.out
    # Without it the same core passes the memory check (and would be synthesised).
    four = StereoParams(transform="census", block=5, disparities=64, rounds=4,
                        aggregation="sgm", p1=16, p2=96, p2_adapt=4, width=1920, height=1080)
    assert memory_fit_message(memory_bits(four), target_device("ecp5", "ecp5-85k"),
                              core_block_rams(four)) is None
