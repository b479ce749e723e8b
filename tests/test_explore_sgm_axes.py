"""``npstereo explore``'s SGM axes (issue 28): ``--fifth-path off on`` and ``--cost-term
none ad3`` multiply the SGM configurations of the grid (a box is taken once, without them),
are in the labels, the JSON and the markdown, are scored by the golden model and refused for
their block RAM like any other configuration; asked for without SGM, or with an unknown
value, they are one line and exit code 2.
"""

import dataclasses
import json

import pytest

from npstereo.gen.cli.cmd_explore import _short_labels
from npstereo.gen.cli.main import main
from npstereo.gen.explore import explorer
from npstereo.gen.explore.explorer import Grid, _label, configurations, plan_tasks
from npstereo.gen.flow.capacity import DEVICES
from npstereo.gen.matching import match_images
from npstereo.golden.quality import evaluate
from npstereo.golden.synthetic import synthetic_pair
from npstereo.params import StereoParams

QUALITY_FIGURES = ("correct", "density", "error_rate", "evaluated")


def test_fifth_path_and_cost_term_axes():
    """The SGM axes multiply the SGM configurations; a box is taken once, without them."""
    grid = Grid(("census",), (5,), (2,), (3, "sgm"), ("auto",), 8, 32, 8,
                fifth_paths=(False, True), cost_terms=(None, "ad3"))
    chosen, skipped = configurations(grid)
    assert skipped == []
    assert [(p.aggregation, p.fifth_path, p.cost_term, p.p2) for p in chosen] == [
        (3, False, None, None), ("sgm", False, None, 79), ("sgm", False, "ad3", 72),
        ("sgm", True, None, 79), ("sgm", True, "ad3", 72)]
    assert [_label(p) for p in chosen[3:]] == ["census 5x5 R=2 A=sgm fifth path",
                                              "census 5x5 R=2 A=sgm +ad3 fifth path"]
    points = [{"params": dataclasses.asdict(p)} for p in chosen]
    assert _short_labels(points) == [
        "census 5 A=3 no term 4 paths", "census 5 A=sgm no term 4 paths",
        "census 5 A=sgm +ad3 4 paths", "census 5 A=sgm no term 5 paths",
        "census 5 A=sgm +ad3 5 paths"]


@pytest.mark.parametrize("options, message", [
    (["--fifth-path", "on"],
     "--fifth-path on is an SGM option: it needs sgm among the --aggregation values"),
    (["--fifth-path"],
     "--fifth-path on is an SGM option: it needs sgm among the --aggregation values"),
    (["--cost-term", "none", "ad3", "--fifth-path", "off", "on"],
     "--fifth-path on and --cost-term ad3 are SGM options: they need sgm among the "
     "--aggregation values"),
    (["--aggregation", "sgm", "--cost-term", "ad3", "--transform", "rank"],
     "cost term ad3 needs the census transform, not rank"),
    (["--aggregation", "sgm", "--cost-term", "ad4"],
     "npstereo explore: argument --cost-term: invalid choice: 'ad4' (choose from 'none', "
     "'ad3')"),
    (["--aggregation", "sgm", "--fifth-path", "both"],
     "npstereo explore: argument --fifth-path: invalid choice: 'both' (choose from 'off', "
     "'on')"),
    (["--aggregation", "sgm", "--cost-term"], "the grid is empty: --cost-term has no values"),
])
def test_sgm_axes_bad_input_is_one_whole_line(options, message, capsys, tmp_path):
    out, cache = tmp_path / "out", tmp_path / "cache"
    argv = ["explore", "--synthetic", "--block", "5", "--rounds", "2", "--disparities", "8",
            "--width", "32", "--height", "8", "--device", "ecp5-25k", "--transform",
            "census", *options, "--out", str(out), "--cache", str(cache)]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [f"npstereo: error: {message}"]
    assert "Traceback" not in captured.err + captured.out
    assert not out.exists() and not cache.exists()


@pytest.mark.dask
def test_explore_fifth_path_and_cost_term_through_the_command(tmp_path):
    """The four SGM combinations of the two axes through the whole command, 2048 x 16 on
    the ECP5-25k: every one is refused for its block RAM (57 DP16KD with four paths, 90
    with five, of 56) without a synthesis, and its quality is the golden model's."""
    out = tmp_path / "o"
    argv = ["explore", "--synthetic", "--transform", "census", "--block", "5", "--rounds",
            "2", "--aggregation", "sgm", "--fifth-path", "off", "on", "--cost-term", "none",
            "ad3", "--disparities", "16", "--width", "2048", "--height", "16", "--device",
            "ecp5-25k", "--workers", "1", "--cache", str(tmp_path / "cache"),
            "--out", str(out)]
    assert main(argv) == 0
    document = json.loads((out / "explore.json").read_text())
    points = document["points"]
    assert [(p["params"]["fifth_path"], p["params"]["cost_term"]) for p in points] == [
        (False, None), (False, "ad3"), (True, None), (True, "ad3")]
    assert [p["verdict"] for p in points] == ["does not fit (memory 102 %)"] * 2 + [
        "does not fit (memory 161 %)"] * 2
    assert [p["synthesis"]["expected_block_rams"] for p in points] == [57, 57, 90, 90]
    assert document["tasks"]["submitted"] == 4       # the quality tasks only
    pair = synthetic_pair(2048, 16, 16, seed=0)
    left, right = pair.gray()
    for point in points:
        params = StereoParams(**point["params"])
        expected = evaluate(match_images(left, right, params), pair.ground_truth, 16)
        assert {k: point["quality"]["clean"][k] for k in QUALITY_FIGURES} == \
            expected.as_dict()
    # Each option is scored with it on: the four maps differ.
    assert len({point["quality"]["clean"]["correct"] for point in points}) == 4
    text = (out / "explore.md").read_text()
    assert "| census 5x5 R=2 A=sgm +ad3 fifth path |" in text
    assert text.count("does not fit (memory 161 %)") == 2


def test_each_option_is_a_quality_task_of_its_own(monkeypatch):
    """The quality key holds the SGM options: the four combinations are four golden-model
    tasks. Broken variant: a key without them (the options dropped before the golden model
    runs) makes the four two tasks (the ad3 ones keep their P2 of 72), and the dask test
    above would find their maps equal in pairs."""
    grid = Grid(("census",), (5,), (2,), ("sgm",), ("auto",), 16, 2048, 16,
                fifth_paths=(False, True), cost_terms=(None, "ad3"))
    configs, _ = configurations(grid)
    pair = synthetic_pair(64, 16, 16, seed=0)
    scenes = {"clean": (*pair.gray(), pair.ground_truth)}
    dev = DEVICES["ecp5-25k"]

    def quality_tasks():
        plan = plan_tasks(configs, scenes, dev, False, 150.0, None, None, None)
        return [t for t in plan.tasks if t.label.startswith("quality")]
    assert len(quality_tasks()) == 4
    golden = explorer._golden
    monkeypatch.setattr(explorer, "_golden", lambda params: golden(
        params.replace(fifth_path=False, cost_term=None)))
    assert len(quality_tasks()) == 2
