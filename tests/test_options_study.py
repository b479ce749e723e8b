"""docs/sgm/options_study.py's options against plain implementations written from its
docstring: the path from the right, the uniqueness test, the median variants."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from npstereo.golden.median import median3

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "sgm"))
import options_study  # noqa: E402
from left_path_study import rows_json  # noqa: E402


def plain_right_path(volume, p1, p2, guide, adapt):
    """L(x, d) = C + min(L(x+1, d), L(x+1, d+-1) + P1, m + P2(x)) - m, m = min L(x+1, .)."""
    height, width, disparities = volume.shape
    out = np.zeros_like(volume)
    for y in range(height):
        out[y, width - 1] = volume[y, width - 1]
        for x in range(width - 2, -1, -1):
            step = abs(int(guide[y, x]) - int(guide[y, x + 1]))
            penalty = max(p1, p2 >> max(0, step.bit_length() - adapt))
            previous = out[y, x + 1]
            low = int(previous.min())
            for d in range(disparities):
                candidates = [previous[d], low + penalty]
                candidates += [previous[d - 1] + p1] if d > 0 else []
                candidates += [previous[d + 1] + p1] if d < disparities - 1 else []
                out[y, x, d] = volume[y, x, d] + min(candidates) - low
    return out


@pytest.mark.parametrize("seed", range(3))
def test_right_path_is_exact_sgm_from_the_right(seed):
    rng = np.random.default_rng(seed)
    volume = rng.integers(0, 20, (3, 11, 5))
    guide = rng.integers(0, 256, (3, 11)).astype(np.uint8)
    got = options_study.right_path(volume, 3, 15, guide, 2, 20)
    assert np.array_equal(got, plain_right_path(volume, 3, 15, guide, 2))
    # Counterpart: the path from the left is another one.
    assert not np.array_equal(got, plain_right_path(volume[:, ::-1], 3, 15, guide[:, ::-1],
                                                    2)[:, ::-1])


def test_uniqueness_rejects_as_opencv_with_u_100_over_2k():
    summed = np.array([[[10, 11, 30, 10, 50],     # an equal far minimum: rejected
                        [10, 11, 30, 12, 50],     # 12: within 25 % but not 12.5 %
                        [10, 9, 12, 30, 13]]])    # 13 > 9 / (1 - 1/4): kept
    assert options_study.uniqueness_reject(summed, 2).tolist() == [[True, True, False]]
    assert options_study.uniqueness_reject(summed, 3).tolist() == [[True, False, False]]


def test_study_median_fill_is_the_golden_median():
    rng = np.random.default_rng(0)
    disparity = np.where(rng.random((9, 12)) < 0.3, -1, rng.integers(0, 8, (9, 12)))
    disparity = disparity.astype(np.int16)
    assert np.array_equal(options_study.median3(disparity, "fill"), median3(disparity))
    valid = options_study.median3(disparity, "valid")
    assert ((valid < 0) == (disparity < 0)).all()          # never fills
    assert not np.array_equal(valid, median3(disparity))


def test_only_one_group_keeps_the_other_rows(tmp_path, monkeypatch, capsys):
    """``--only GROUP`` replaces that group's rows of ``--out`` and keeps every other row;
    ``group_of`` names the group of every row the study stores."""
    rows = [dict(scene="teddy", method="OpenCV StereoSGBM MODE_HH", lr="yes", correct=1.0),
            dict(scene="teddy", cost="census", p1=24, p2=79, adapt=5, paths=4, uniq=0,
                 lr="yes", median="none", correct=2.0),
            dict(scene="teddy", cost="census", p1=8, p2=48, adapt=3, paths=5, uniq=0,
                 lr="yes", median="none", correct=3.0),
            dict(scene="teddy", cost="ad3", p1=24, p2=72, adapt=5, paths=5, uniq=0,
                 lr="yes", median="fill", correct=4.0),
            dict(scene="teddy", cost="census", p1=24, p2=79, adapt=5,
                 paths=options_study.TRACKED, uniq=0, lr="yes", median="none", correct=5.0)]
    assert [options_study.group_of(r) for r in rows] == [
        "peers", "census", "census wide", "ad3", "fifth"]
    out = tmp_path / "study.json"
    out.write_text(rows_json(rows))
    fresh = dict(rows[-1], correct=6.0)
    monkeypatch.setattr(options_study, "measure", lambda dataset, group: iter([fresh]))
    monkeypatch.setattr(options_study, "report", lambda got: f"{len(got)} rows")
    assert options_study.main(["--dataset", str(tmp_path), "--out", str(out),
                               "--only", "fifth"]) == 0
    assert json.loads(out.read_text())["rows"] == rows[:-1] + [fresh]
    assert "5 rows" in capsys.readouterr().out
