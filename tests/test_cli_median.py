"""``--median`` on the command line: the map it gives, and a median that is not a bool
refused (``npstereo prove`` takes the median since issue 28's loose ends: tests/test_prove.py)."""

import json

import numpy as np
import pytest

from npstereo.gen.cli.main import main
from npstereo.golden.median import median3
from npstereo.golden.pipeline import disparity_map
from npstereo.golden.quality import evaluate
from npstereo.params import ParameterError, StereoParams

from test_cli_sgm import D, run_match


@pytest.mark.parametrize("options", [(), ("--aggregation", "sgm", "--block", "5")])
def test_match_median_is_the_median_of_the_map(capsys, tmp_path, pair_files, small_pair,
                                               options):
    got = run_match(tmp_path, pair_files, "median", "--median", *options)
    plain = run_match(tmp_path, pair_files, "plain", *options)
    assert np.array_equal(got, median3(plain))
    assert not np.array_equal(got, plain)      # the option is not lost on the way
    params = StereoParams(transform="census", block=5 if options else 9, disparities=D,
                          aggregation="sgm" if options else 3, median=True)
    assert np.array_equal(got, disparity_map(*small_pair.gray(), params).disparity)
    assert " median" in capsys.readouterr().out


def test_median_must_be_a_bool():
    with pytest.raises(ParameterError, match="median must be True or False, not 'yes'"):
        StereoParams(median="yes")


def test_eval_names_the_median(capsys, tmp_path, pair_files, small_pair):
    _, _, scene = pair_files
    result = tmp_path / "median.json"
    assert main(["eval", "--dataset", str(scene), "--block", "5", "--aggregation", "sgm",
                 "--median", "--disparities", str(D), "--json", str(result)]) == 0
    assert "SGM P1=24 P2=79 t=5, 3x3 median" in capsys.readouterr().out
    (row,) = json.loads(result.read_text())
    assert row["median"] is True
    params = StereoParams("census", 5, D, aggregation="sgm", median=True)
    truth = (4 * small_pair.ground_truth).astype(np.uint8) / 4.0
    expected = evaluate(disparity_map(*small_pair.gray(), params).disparity, truth, D)
    assert row["correct"] == pytest.approx(expected.correct)
