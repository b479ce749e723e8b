"""``--aggregation sgm`` on the command line: the maps it gives and every bad input.

The maps are compared with the golden model called directly (golden.sgm), not only with
the pipeline the commands use, so a command that loses a penalty on the way fails here.
The hardware commands build the SGM core at any R dividing D, and refuse others in one line.
"""

import json

import numpy as np
import pytest

from npstereo.gen.cli.main import main
from npstereo.golden import sgm
from npstereo.golden.pipeline import disparity_map
from npstereo.golden.quality import evaluate
from npstereo.params import SGM_DEFAULT_ADAPT, SGM_DEFAULT_P1, SGM_DEFAULT_P2, StereoParams

D = 16


def run_match(tmp_path, pair_files, name, *options):
    """The raw map ``npstereo match`` writes with ``options``."""
    left, right, _ = pair_files
    raw = tmp_path / f"{name}.npy"
    assert main(["match", str(left), str(right), "--disparities", str(D),
                 "--out", str(tmp_path / f"{name}.png"), "--raw", str(raw), *options]) == 0
    return np.load(raw)


def test_match_sgm_is_the_golden_sgm_map(capsys, tmp_path, pair_files, small_pair):
    got = run_match(tmp_path, pair_files, "sgm", "--block", "5", "--aggregation", "sgm",
                    "--p1", "10", "--p2", "60", "--p2-adapt", "4")
    gray = small_pair.gray()
    params = StereoParams(transform="census", block=5, disparities=D)
    expected = sgm.disparity_map(*gray, params, 10, 60, adapt=4).disparity
    assert np.array_equal(got, expected)
    assert "SGM P1=10 P2=60 t=4" in capsys.readouterr().out
    # Counterpart: the box of the same transform is another map.
    assert not np.array_equal(got, disparity_map(*gray, params).disparity)


def test_match_sgm_defaults_and_constant_p2(tmp_path, pair_files, small_pair):
    gray = small_pair.gray()
    defaults = run_match(tmp_path, pair_files, "defaults", "--block", "7",
                         "--aggregation", "sgm")
    params = StereoParams(transform="census", block=7, disparities=D)
    assert np.array_equal(defaults, sgm.disparity_map(
        *gray, params, SGM_DEFAULT_P1, SGM_DEFAULT_P2, adapt=SGM_DEFAULT_ADAPT).disparity)
    constant = run_match(tmp_path, pair_files, "constant", "--block", "7",
                         "--aggregation", "sgm", "--no-p2-adapt", "--no-lr-check")
    expected = sgm.disparity_map(*gray, params.replace(lr_threshold=None), SGM_DEFAULT_P1,
                                 SGM_DEFAULT_P2).disparity
    assert np.array_equal(constant, expected)
    # Counterpart: adaptive P2 changes this map, so dropping --no-p2-adapt would fail above.
    assert not np.array_equal(expected, sgm.disparity_map(
        *gray, params.replace(lr_threshold=None), SGM_DEFAULT_P1, SGM_DEFAULT_P2,
        adapt=SGM_DEFAULT_ADAPT).disparity)


def test_eval_takes_a_grid_of_aggregations(capsys, tmp_path, pair_files, small_pair):
    _, _, scene = pair_files
    result = tmp_path / "grid.json"
    assert main(["eval", "--dataset", str(scene), "--block", "5", "7", "--aggregation", "3",
                 "sgm", "--p1", "12", "--disparities", str(D), "--json", str(result)]) == 0
    table = capsys.readouterr().out
    rows = json.loads(result.read_text())
    assert [(r["block"], r["aggregation"], r["p1"], r["p2"], r["p2_adapt"]) for r in rows] == [
        (5, 3, None, None, None), (5, "sgm", 12, 79, 5),
        (7, 3, None, None, None), (7, "sgm", 12, 79, 5)]
    gray = small_pair.gray()
    truth = (4 * small_pair.ground_truth).astype(np.uint8) / 4.0
    for row in rows:
        params = StereoParams("census", row["block"], D)
        if row["aggregation"] == "sgm":
            disparity = sgm.disparity_map(*gray, params, 12, 79, adapt=5).disparity
        else:
            disparity = disparity_map(*gray, params).disparity
        expected = evaluate(disparity, truth, D).correct
        assert row["correct"] == pytest.approx(expected)
        assert f"| {row['aggregation_label']} | {expected:.2f} |" in table
    assert rows[0]["correct"] != rows[1]["correct"]


def files_under(path):
    return sorted(p.relative_to(path) for p in path.rglob("*"))


def assert_exact_user_error(capsys, root, argv, message):
    """Exit code 2, exactly ``npstereo: error: <message>`` on stderr, no new file."""
    before = files_under(root)
    code = main(argv)
    captured = capsys.readouterr()
    assert (code, captured.err) == (2, f"npstereo: error: {message}\n")
    assert files_under(root) == before


def test_exact_error_check_can_fail(capsys, tmp_path, pair_files):
    # Not vacuous: a command that works, and a wrong message, both fail the check.
    left, right, _ = pair_files
    good = ["match", str(left), str(right), "--disparities", str(D), "--block", "5",
            "--aggregation", "sgm", "--out", str(tmp_path / "ok.png")]
    with pytest.raises(AssertionError):
        assert_exact_user_error(capsys, tmp_path, good, "anything")
    with pytest.raises(AssertionError):
        assert_exact_user_error(capsys, tmp_path, good[:-2] + ["--p1", "-1", "--out",
                                                               str(tmp_path / "x.png")],
                                "P1 must be an integer >= 0, not -2")


#: Census 7x7, D = 16 at the commands' default R = 1 (command_line below).
#: SGM takes any R that divides D (the left path tracks its reference, docs/sgm.md); the
#: one rule left on R is the box's.
ROUNDS_NOT_DIVIDING = "rounds must divide disparities (16), not 3"

#: Options that a grid command (eval) accepts: two aggregations are two configurations.
GRID = [["--aggregation", "sgm", "--aggregation", "3"],
        ["--aggregation", "3", "--aggregation", "5"]]

#: (options after the command's own, exact message; ``{command}`` is the command's name).
BAD = [
    (["--aggregation", "sgm", "--p1", "-1"], "P1 must be an integer >= 0, not -1"),
    (["--aggregation", "sgm", "--p2", "-3"],
     "P2 must be an integer >= P1 (24), not -3 (SGM defaults P1 = 24, P2 = 79)"),
    (["--aggregation", "sgm", "--p1", "30", "--p2", "20"],
     "P2 must be an integer >= P1 (30), not 20"),
    (["--aggregation", "sgm", "--p1", "1", "--p2", "104", "--block", "5"],
     "P2 must be <= 103 for a matching cost of at most 24 (path cost at most 7 bits), not 104"),
    (["--aggregation", "sgm", "--block", "3"],
     "P2 must be <= 55 for a matching cost of at most 8 (path cost at most 6 bits), not 79 "
     "(SGM defaults P1 = 24, P2 = 79)"),
    (["--aggregation", "sgm", "--p2-adapt", "8"],
     "adaptive P2 exponent must be an integer 1 .. 7 (or off), not 8"),
    (["--p1", "3"], "--p1 is an SGM option: it needs --aggregation sgm"),
    (["--aggregation", "5", "--p2", "9", "--no-p2-adapt"],
     "--p2 and --no-p2-adapt are SGM options: they need --aggregation sgm"),
    (["--aggregation", "sgm", "--aggregation", "3"],
     "--aggregation sgm replaces the aggregation window: give sgm or a window size, not both "
     "(sgm and 3)"),
    (["--aggregation", "3", "--aggregation", "5"],
     "--aggregation takes one value for one configuration, not 3 5"),
    (["--aggregation", "box"],
     "npstereo {command}: argument --aggregation: must be an odd window size or sgm, not 'box'"),
    (["--aggregation", "2"], "aggregation must be an odd window size >= 1 or 'sgm', not 2"),
    (["--aggregation", "sgm", "--p2-adapt", "3", "--no-p2-adapt"],
     "npstereo {command}: argument --no-p2-adapt: not allowed with argument --p2-adapt"),
]


def command_line(command, tmp_path, pair_files):
    """Arguments of ``command`` without its matching options (census 7x7, D = 16)."""
    left, right, scene = pair_files
    common = ["--block", "7", "--disparities", str(D)]
    return {
        "match": ["match", str(left), str(right), "--out", str(tmp_path / "o" / "d.png")],
        "eval": ["eval", "--dataset", str(scene), "--json", str(tmp_path / "o" / "e.json")],
        "verilog": ["verilog", "--width", "64", "--height", "8",
                    "--out", str(tmp_path / "o" / "c.v")],
        "cosim": ["cosim", "--simulator", "icarus", "--dataset", str(scene),
                  "--out", str(tmp_path / "o" / "cosim")],
        "report": ["report", "--width", "64", "--height", "8", "--json",
                   str(tmp_path / "o" / "r.json")],
    }[command] + common


@pytest.mark.parametrize("command", ["match", "eval", "verilog", "cosim", "report"])
@pytest.mark.parametrize("options, message", BAD, ids=[" ".join(o) for o, _ in BAD])
def test_bad_sgm_options_exit_2_with_one_line(capsys, tmp_path, pair_files, command, options,
                                              message):
    if command == "eval" and options in GRID:
        pytest.skip("eval takes several aggregations as a grid")
    argv = command_line(command, tmp_path, pair_files) + options
    assert_exact_user_error(capsys, tmp_path, argv, message.format(command=command))


@pytest.mark.parametrize("command", ["verilog", "cosim", "report"])
def test_several_values_after_one_option(capsys, tmp_path, pair_files, command):
    # The hardware commands take --aggregation's values as a list, so both spellings of
    # "sgm and a window" get the same message (match takes one value per option).
    argv = command_line(command, tmp_path, pair_files) + ["--aggregation", "sgm", "3"]
    message = next(m for o, m in BAD if o == GRID[0])
    assert_exact_user_error(capsys, tmp_path, argv, message)


@pytest.mark.parametrize("command", ["verilog", "cosim", "report"])
def test_hardware_commands_refuse_rounds_not_dividing_d(capsys, tmp_path, pair_files,
                                                       command):
    argv = command_line(command, tmp_path, pair_files) + ["--aggregation", "sgm",
                                                          "--rounds", "3"]
    assert_exact_user_error(capsys, tmp_path, argv, ROUNDS_NOT_DIVIDING)


def test_verilog_and_cosim_build_the_sgm_core(capsys, tmp_path, pair_files):
    """The Verilog records the penalties, and Amaranth's simulator gives the golden SGM
    map on a crop of the pair at R = 1 (all D disparities per clock)."""
    sgm_options = ["--aggregation", "sgm", "--rounds", "8", "--p1", "16", "--p2", "90"]
    assert main(command_line("verilog", tmp_path, pair_files) + sgm_options) == 0
    head = (tmp_path / "o" / "c.v").read_text()[:1000]
    assert "aggregation=sgm p1=16 p2=90 p2_adapt=5" in head
    _, _, scene = pair_files
    assert main(["cosim", "--simulator", "amaranth", "--dataset", str(scene), "--crop", "24x6",
                 "--out", str(tmp_path / "cosim"), "--block", "3", "--disparities", str(D),
                 "--aggregation", "sgm", "--rounds", "1", "--p1", "4", "--p2", "40"]) == 0
    assert "mismatches:       0 (bit-exact)" in capsys.readouterr().out


def test_eval_grid_keeps_the_penalty_checks(capsys, tmp_path, pair_files):
    # In a grid the box configurations take no penalties, the SGM ones are checked.
    argv = command_line("eval", tmp_path, pair_files) + ["--aggregation", "3", "sgm",
                                                         "--p1", "-1"]
    assert_exact_user_error(capsys, tmp_path, argv, "P1 must be an integer >= 0, not -1")
