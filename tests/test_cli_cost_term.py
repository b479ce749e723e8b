"""``--cost-term ad3`` on the command line: the map it gives, the core it builds, and what
refuses it in one line."""

import json

import numpy as np
import pytest

from npstereo.gen.cli.main import main
from npstereo.golden import sgm
from npstereo.golden.pipeline import disparity_map
from npstereo.params import StereoParams

from test_cli_sgm import D, assert_exact_user_error, command_line, run_match


def test_match_with_the_term_is_the_golden_map(capsys, tmp_path, pair_files, small_pair):
    got = run_match(tmp_path, pair_files, "ad3", "--block", "5", "--aggregation", "sgm",
                    "--cost-term", "ad3", "--p2", "60")
    params = StereoParams("census", 5, D, aggregation="sgm", cost_term="ad3", p2=60)
    gray = small_pair.gray()
    assert np.array_equal(got, disparity_map(*gray, params).disparity)
    assert "census+ad3 5x5" in capsys.readouterr().out
    # Counterpart: the term changes this map, so losing the flag on the way fails above.
    assert not np.array_equal(got, sgm.disparity_map(*gray, params.replace(cost_term=None),
                                                     24, 60, adapt=5).disparity)


def test_eval_names_the_term_and_its_default_p2(capsys, tmp_path, pair_files):
    argv = command_line("eval", tmp_path, pair_files) + ["--aggregation", "sgm",
                                                         "--cost-term", "ad3"]
    assert main(argv) == 0
    assert "SGM P1=24 P2=72 t=5, + ad3" in capsys.readouterr().out
    (row,) = json.loads((tmp_path / "o" / "e.json").read_text())
    assert (row["cost_term"], row["p2"]) == ("ad3", 72)


def test_verilog_records_the_term(tmp_path, pair_files):
    argv = command_line("verilog", tmp_path, pair_files) + ["--aggregation", "sgm",
                                                            "--cost-term", "ad3"]
    assert main(argv) == 0
    head = (tmp_path / "o" / "c.v").read_text()[:1000]
    assert "aggregation=sgm p1=24 p2=72 p2_adapt=5 cost_term=ad3" in head


#: (options after the command's own, exact message).
BAD = [
    (["--cost-term", "ad3"], "--cost-term is an SGM option: it needs --aggregation sgm"),
    (["--aggregation", "3", "--cost-term", "ad3", "--p1", "4"],
     "--p1 and --cost-term are SGM options: they need --aggregation sgm"),
    (["--aggregation", "sgm", "--cost-term", "ad3", "--transform", "rank"],
     "cost term ad3 needs the census transform, not rank"),
    (["--aggregation", "sgm", "--cost-term", "ad4"],
     "cost term must be one of ad3 (or none), not 'ad4'"),
    (["--aggregation", "sgm", "--cost-term", "ad3", "--p2", "201"],
     "P2 must be <= 200 for a matching cost of at most 55 (path cost at most 8 bits), not "
     "201 (SGM defaults P1 = 24, P2 = 72)"),
]


@pytest.mark.parametrize("command", ["match", "eval", "verilog", "cosim", "report"])
@pytest.mark.parametrize("options, message", BAD, ids=[" ".join(o) for o, _ in BAD])
def test_bad_term_options_exit_2_with_one_line(capsys, tmp_path, pair_files, command,
                                               options, message):
    argv = command_line(command, tmp_path, pair_files) + options
    assert_exact_user_error(capsys, tmp_path, argv, message)
