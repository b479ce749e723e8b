"""The match, eval, paper and demo commands: results on synthetic data and every bad input."""

import json
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from npstereo.gen.cli.main import main
from npstereo.params import SGM_DEFAULT_ADAPT, SGM_DEFAULT_P1, SGM_DEFAULT_P2, StereoParams
from npstereo.golden import sgm
from npstereo.golden.pipeline import disparity_map
from npstereo.golden.quality import evaluate
from npstereo.golden.synthetic import synthetic_pair

D = 16


def files_under(path):
    return sorted(p.relative_to(path) for p in path.rglob("*"))


def assert_user_error(capsys, root, argv, *words):
    """Exit code 2, one line on stderr naming ``words``, no traceback, no new file."""
    before = files_under(root)
    code = main(argv)
    captured = capsys.readouterr()
    assert code == 2, captured
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("npstereo: error: "), captured.err
    assert "Traceback" not in captured.err + captured.out
    for word in words:
        assert word in lines[0]
    assert files_under(root) == before


def test_user_error_check_fails_on_a_good_command(capsys, tmp_path, pair_files):
    left, right, _ = pair_files
    with pytest.raises(AssertionError, match="assert 0 == 2"):
        assert_user_error(capsys, tmp_path, ["match", str(left), str(right), "--block", "5",
                                             "--disparities", str(D),
                                             "--out", str(tmp_path / "ok.png")])


def test_match_writes_png_and_raw(capsys, tmp_path, pair_files, small_pair):
    left, right, _ = pair_files
    out, raw = tmp_path / "out" / "d.png", tmp_path / "out" / "d.npy"
    assert main(["match", str(left), str(right), "--transform", "ext-rank", "--block", "5",
                 "--disparities", str(D), "--rounds", "4", "--out", str(out),
                 "--raw", str(raw)]) == 0
    gray = small_pair.gray()
    expected = disparity_map(*gray, StereoParams("ext-rank", 5, D, rounds=4)).disparity
    saved = np.load(raw)
    assert saved.dtype == np.int16 and np.array_equal(saved, expected)
    png = np.asarray(Image.open(out))
    assert png.shape == expected.shape + (3,)
    assert (png[expected < 0] == 0).all() and (png[expected >= 0].sum(axis=-1) > 0).all()
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["d.npy", "d.png"]


def test_match_lr_options(tmp_path, pair_files, small_pair):
    left, right, _ = pair_files
    raw = tmp_path / "n.npy"
    assert main(["match", str(left), str(right), "--block", "3", "--disparities", str(D),
                 "--no-lr-check", "--out", str(tmp_path / "n.png"), "--raw", str(raw)]) == 0
    unchecked = np.load(raw)
    assert (unchecked[:, D:] >= 0).all()
    assert main(["match", str(left), str(right), "--block", "3", "--disparities", str(D),
                 "--lr-threshold", "0", "--out", str(tmp_path / "t.png"),
                 "--raw", str(raw)]) == 0
    assert (np.load(raw)[:, D:] < 0).any()


def test_match_bad_inputs(capsys, tmp_path, pair_files):
    left, right, _ = pair_files
    out = str(tmp_path / "o" / "d.png")
    common = ["--disparities", str(D), "--out", out]
    junk = tmp_path / "junk.png"
    junk.write_text("hello")
    small = tmp_path / "small.png"
    Image.fromarray(np.zeros((40, 63), np.uint8)).save(small)
    narrow = tmp_path / "narrow.png"
    Image.fromarray(np.zeros((40, 16), np.uint8)).save(narrow)
    cases = [
        (["match", str(tmp_path / "missing.png"), str(right)] + common, "missing.png"),
        (["match", str(junk), str(right)] + common, "not a readable image"),
        (["match", str(left), str(small)] + common, "differ in size"),
        (["match", str(narrow), str(narrow)] + common, "width"),
        (["match", str(left), str(right), "--block", "x"] + common, "invalid int"),
        (["match", str(left), str(right), "--block", "4"] + common, "block"),
        (["match", str(left), str(right), "--block", "1"] + common, "block"),
        (["match", str(left), str(right), "--transform", "sad"] + common, "transform"),
        (["match", str(left), str(right), "--rounds", "3"] + common, "rounds"),
        (["match", str(left), str(right), "--aggregation", "2"] + common, "aggregation"),
        (["match", str(left), str(right), "--lr-threshold", "-1"] + common, "lr threshold"),
        (["match", str(left), str(right), "--disparities", "1", "--out", out], "disparities"),
        (["match", str(left), str(right), "--disparities", str(D), "--out", "d.jpg"], ".png"),
        (["match", str(left), str(right), "--raw", "d.txt"] + common, ".npy"),
        (["match", str(left), str(right), "--lr-threshold", "2", "--no-lr-check"] + common,
         "not allowed"),
        (["match", str(left)] + common, "required"),
        (["match", str(left), str(right), "--disparities", str(D), "--out",
          str(junk / "d.png")], "not a folder"),
    ]
    for argv, word in cases:
        assert_user_error(capsys, tmp_path, argv, word)


def test_eval_reports_the_metric(capsys, tmp_path, pair_files, small_pair):
    _, _, scene = pair_files
    result = tmp_path / "r" / "e.json"
    assert main(["eval", "--dataset", str(scene), "--transform", "census", "rank",
                 "--block", "3", "5", "--disparities", str(D), "--json", str(result)]) == 0
    table = capsys.readouterr().out
    rows = json.loads(result.read_text())
    assert [(r["transform"], r["block"]) for r in rows] == [
        ("census", 3), ("census", 5), ("rank", 3), ("rank", 5)]
    gray = small_pair.gray()
    truth = (4 * small_pair.ground_truth).astype(np.uint8) / 4.0
    for row in rows:
        params = StereoParams(row["transform"], row["block"], D)
        expected = evaluate(disparity_map(*gray, params).disparity, truth, D)
        assert row["correct"] == pytest.approx(expected.correct)
        assert f"{expected.correct:.2f}" in table


def test_eval_degradations_change_the_result(capsys, tmp_path, pair_files):
    _, _, scene = pair_files
    base = ["eval", "--dataset", str(scene), "--block", "5", "--disparities", str(D)]
    outcomes = {}
    for name, extra in [("clean", []), ("noise", ["--noise", "0.01", "--seed", "3"]),
                        ("bayer", ["--bayer", "--bayer-gains", "0.5", "1", "0.7"])]:
        path = tmp_path / f"{name}.json"
        assert main(base + extra + ["--json", str(path)]) == 0
        outcomes[name] = json.loads(path.read_text())[0]
    capsys.readouterr()
    assert outcomes["noise"]["condition"] == "noise 0.01"
    assert outcomes["noise"]["correct"] < outcomes["clean"]["correct"]
    assert outcomes["bayer"]["correct"] != outcomes["clean"]["correct"]


def test_eval_bad_inputs(capsys, tmp_path, pair_files):
    _, _, scene = pair_files
    empty = tmp_path / "empty"
    empty.mkdir()
    common = ["--disparities", str(D), "--json", str(tmp_path / "o" / "r.json")]
    cases = [
        (["eval", "--dataset", str(tmp_path / "none")] + common, "does not exist"),
        (["eval", "--dataset", str(empty)] + common, "unknown dataset layout"),
        (["eval", "--dataset", str(scene), "--noise", "-1"] + common, "variance"),
        (["eval", "--dataset", str(scene), "--noise", "abc"] + common, "invalid float"),
        (["eval", "--dataset", str(scene), "--block", "3", "6"] + common, "block"),
        (["eval", "--dataset", str(scene), "--jobs", "0"] + common, "--jobs"),
        (["eval", "--dataset", str(scene), "--read-noise", "2"] + common, "--bayer"),
        (["eval", "--dataset", str(scene), "--disparities", str(D), "--json", "r.txt"],
         ".json"),
    ]
    for argv, word in cases:
        assert_user_error(capsys, tmp_path, argv, word)
    gray_scene = tmp_path / "gray"
    gray_scene.mkdir()
    for name in ("im2.png", "im6.png"):
        Image.fromarray(np.asarray(Image.open(scene / name).convert("L"))).save(gray_scene / name)
    Image.open(scene / "disp2.pgm").save(gray_scene / "disp2.pgm")
    assert_user_error(capsys, tmp_path, ["eval", "--dataset", str(gray_scene), "--bayer"]
                      + common, "colour")
    Image.fromarray(np.zeros((40, 64), np.uint16)).save(gray_scene / "d.png")
    (gray_scene / "d.png").replace(gray_scene / "disp2.pgm")
    assert_user_error(capsys, tmp_path, ["eval", "--dataset", str(gray_scene)] + common,
                      "8-bit")
    Image.fromarray(np.zeros((40, 60), np.uint8)).save(gray_scene / "disp2.pgm")
    assert_user_error(capsys, tmp_path, ["eval", "--dataset", str(gray_scene)] + common,
                      "60x40")


def test_paper_on_the_synthetic_scene(capsys, tmp_path):
    out = tmp_path / "paper"
    assert main(["paper", "--synthetic", "--out", str(out), "--blocks", "3",
                 "--disparities", str(D)]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == ["README.md", "bayer1.png", "bayer2.png", "fig12.png", "fig6.png",
                     "fig8.png", "ground_truth.png", "results.json"]
    results = json.loads((out / "results.json").read_text())
    assert len(results["results"]) == 4 * 4
    clean = [r for r in results["results"] if r["condition"] == "clean"]
    assert all(r["correct"] > 50 for r in clean)
    readme = (out / "README.md").read_text()
    assert "| census |" in readme
    # The SGM rows are measured: the default and census 5x5 under all four conditions,
    # the clean ones equal to the golden SGM map scored here.
    assert [(r["condition"], r["block"]) for r in results["sgm"]][:4] == [
        ("clean", 7), ("clean", 5), ("noise 0.002", 7), ("noise 0.002", 5)]
    assert len(results["sgm"]) == 2 * 4
    pair = synthetic_pair(disparities=D)
    for row in results["sgm"][:2]:
        params = StereoParams("census", row["block"], D)
        map_ = sgm.disparity_map(*pair.gray(), params, row["p1"], row["p2"],
                                 adapt=row["p2_adapt"] or None).disparity
        expected = evaluate(map_, pair.ground_truth, D)
        assert row["correct"] == pytest.approx(expected.correct)
        assert f"| {row['configuration']} | {expected.correct:.2f} |" in readme
    assert (row["p1"], row["p2"], row["p2_adapt"]) == (16, 96, 4)
    assert results["sgm"][0]["configuration"] == "census 7x7, SGM P1=24 P2=79 t=5 (default)"


def test_paper_and_demo_bad_inputs(capsys, tmp_path):
    a_file = tmp_path / "file"
    a_file.write_text("x")
    cases = [
        (["paper", "--dataset", str(tmp_path / "none"), "--out", str(tmp_path / "p")],
         "does not exist"),
        (["paper", "--synthetic", "--out", str(tmp_path / "p"), "--blocks", "8"], "block"),
        (["paper", "--synthetic", "--out", str(tmp_path / "p"), "--noise", "0"], "--noise"),
        (["paper", "--synthetic", "--out", str(a_file)], "not a folder"),
        (["paper", "--synthetic", "--out", str(tmp_path / "p"), "--jobs", "-2"], "--jobs"),
        (["demo", "--out", str(a_file)], "not a folder"),
        (["demo", "--out", str(tmp_path / "d"), "--block", "2"], "block"),
        (["demo", "--out", str(a_file / "d")], "not a writable folder"),
        (["paper", "--synthetic", "--out", str(a_file / "p")], "not a writable folder"),
    ]
    for argv, word in cases:
        assert_user_error(capsys, tmp_path, argv, word)


def test_demo_writes_maps_and_summary(capsys, tmp_path, default_pair):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--block", "7", "--no-hardware"]) == 0
    summary = json.loads((out / "golden.json").read_text())
    assert [(r["name"], r["transform"], r["block"]) for r in summary["results"]] == [
        ("rank", "rank", 7), ("census", "census", 7), ("ext-rank", "ext-rank", 7),
        ("ext-census", "ext-census", 7), ("sgm", "census", 7)]
    assert all(r["correct"] > 70 for r in summary["results"])
    for name in ("left", "right", "ground_truth", "rank", "census", "ext-rank", "ext-census",
                 "sgm"):
        assert (out / f"{name}.png").stat().st_size > 0
    printed = capsys.readouterr().out
    assert "census" in printed
    text = (out / "summary.md").read_text()
    assert "| ext-census 7x7 | A=3 |" in text
    # The SGM row is the golden SGM map with the defaults, measured.
    row = summary["results"][-1]
    params = StereoParams("census", 7, 32)
    expected = evaluate(sgm.disparity_map(*default_pair.gray(), params, SGM_DEFAULT_P1,
                                          SGM_DEFAULT_P2, adapt=SGM_DEFAULT_ADAPT).disparity,
                        default_pair.ground_truth, 32)
    assert row["correct"] == pytest.approx(expected.correct)
    assert row["aggregation"] == "SGM P1=24 P2=79 t=5"
    assert f"| census 7x7 | SGM P1=24 P2=79 t=5 | {expected.correct:.2f} |" in text
    assert f"census 7x7 SGM P1=24 P2=79 t=5     correct {expected.correct:6.2f}%" in printed


def test_eval_in_parallel_processes_gives_the_same_numbers(capsys, tmp_path, pair_files):
    _, _, scene = pair_files
    rows = {}
    for jobs in ("1", "2"):
        path = tmp_path / f"j{jobs}.json"
        assert main(["eval", "--dataset", str(scene), "--transform", "rank", "ext-census",
                     "--block", "3", "--disparities", str(D), "--jobs", jobs,
                     "--json", str(path)]) == 0
        rows[jobs] = [(r["transform"], r["correct"], r["density"])
                      for r in json.loads(path.read_text())]
    assert rows["1"] == rows["2"] and len(rows["1"]) == 2


def test_console_script_error_has_no_traceback(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "npstereo.gen.cli", "match", str(tmp_path / "a.png"),
         str(tmp_path / "b.png"), "--out", str(tmp_path / "o.png")],
        capture_output=True, text=True, check=False)
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr
    assert list(tmp_path.iterdir()) == []
