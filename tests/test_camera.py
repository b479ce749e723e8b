"""``npstereo report --camera``: the camera-rate configurations, their table and bad input.

The sweep's machinery (tasks, cache, resumption) is the paper sweep's, tested in
tests/test_report.py; here: which configurations it runs, what its table says (frames/s
and disparity evaluations per second beside the peers), and one-line refusals.
"""

import dataclasses
import json

import pytest
from PIL import Image

from npstereo.gen.cli.main import main
from npstereo.gen.cli import cmd_report
from npstereo.gen.reports.camera import PEERS, camera_configurations, evaluations_per_second
from npstereo.gen.reports.tables import camera_markdown
from npstereo.params import StereoParams


def test_camera_configurations_cover_the_issue_grid():
    configurations = camera_configurations()
    keys = {(p.transform, p.block, p.is_sgm, p.width, p.height, p.disparities, p.rounds)
            for p in configurations}
    assert len(keys) == len(configurations) == 2 * 5 * (3 + 2)
    for block in (5, 7):
        for sgm in (True, False):
            for width, height, disparities in ((640, 480, 64), (640, 480, 128),
                                               (1280, 720, 64), (1280, 720, 128),
                                               (1920, 1080, 64)):
                for rounds in (1, 2, 4) if sgm else (1, 2):
                    assert ("census", block, sgm, width, height, disparities, rounds) in keys
    # SGM first: the matcher the camera rates are about.
    sgm = sum(p.is_sgm for p in configurations)
    assert sgm == 2 * 5 * 3 and all(p.is_sgm for p in configurations[:sgm])


def test_peers_are_the_published_rates():
    rates = {name: round(evaluations_per_second(w, h, d, fps) / 1e9, 1)
             for name, w, h, d, fps in PEERS}
    assert list(rates.values()) == [3.2, 4.8, 10.3, 15.9]


def _report(params, ecp5, cyclonev=None):
    results = {"ecp5": ecp5}
    if cyclonev is not None:
        results["cyclonev"] = cyclonev
    return {"params": dataclasses.asdict(params), "results": results}


def test_camera_table_gives_frames_and_evaluations_per_second():
    sgm = StereoParams(transform="census", block=5, disparities=64, rounds=1,
                       aggregation="sgm", width=1280, height=720)
    box = sgm.replace(aggregation=3, rounds=2, p1=None, p2=None, p2_adapt=None)
    placed = {"target": "ecp5", "status": "ok", "logic": 40000, "registers": 50000,
              "block_rams": 124, "utilisation": {"LUT": 67.2}, "pnr": True,
              "fmax_mhz": 100.0, "frames_per_second": 100.0}
    too_big = {"target": "ecp5", "status": "does not fit", "message":
               "does not fit (112 % LUT)", "logic": 93000, "registers": 4000,
               "block_rams": 6, "utilisation": {"LUT": 112.0}, "pnr": True, "fmax_mhz": None}
    cyclone = {"target": "cyclonev", "status": "ok", "logic": 30000, "block_rams": 200}
    text = camera_markdown([_report(sgm, placed, cyclone), _report(box, too_big)])
    # 1280 x 720 x 64 x 100 frames/s = 5.90 G evaluations/s.
    assert ("| census 5x5 SGM | 1280x720 | 64 | 1 | 40,000 | 67 | 50,000 | 124 | 100.0 | "
            "100.0 | 5.90 | 30,000 | 200 |") in text
    assert "| census 5x5 3x3 box | 1280x720 | 64 | 2 | 93,000 | 112 |" in text
    assert "| does not fit (112 % LUT) | - | - | not run | not run |" in text
    assert "| Grabowski & Kryjak 2023 (4 pixels per clock) | 3840x2160 | 64 | 30 | 15.9 |" in text
    assert (f"- {box.describe()} ecp5: does not fit: does not fit (112 % LUT)") in text


def test_camera_sweep_writes_its_documents(tmp_path, monkeypatch):
    """The sweep runs every configuration (here through a fake task runner: real synthesis
    of 40 camera-sized cores takes hours) and writes camera.json, camera.md and the
    evaluations-per-second plot camera.png, not the paper's sweep.json."""
    seen = []

    def fake_sweep(configurations, targets, pnr, freq, timeout, cache, client, progress=None,
                   engine=None, earlier=None):
        seen.extend(configurations)
        reports = [{"params": dataclasses.asdict(p), "results": {"ecp5": {
            "target": "ecp5", "status": "ok", "logic": 1, "registers": 1, "block_rams": 1,
            "pnr": pnr, "fmax_mhz": 150.0, "frames_per_second": 150.0}}}
            for p in configurations]
        progress(reports)
        return reports

    monkeypatch.setattr(cmd_report, "run_sweep", fake_sweep)
    monkeypatch.setattr(cmd_report, "cluster", lambda scheduler, workers: _NoCluster())
    assert main(["report", "--camera", "--target", "ecp5", "--pnr", "--no-cache",
                 "--out", str(tmp_path)]) == 0
    assert seen == camera_configurations()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["camera.json", "camera.md",
                                                          "camera.png"]
    with Image.open(tmp_path / "camera.png") as plot:
        assert plot.format == "PNG" and plot.height > 40 * 12   # 40 rows and 4 peers
    document = json.loads((tmp_path / "camera.json").read_text())
    assert len(document["reports"]) == len(seen)
    assert "| census 5x5 SGM | 1920x1080 | 64 | 1 |" in (tmp_path / "camera.md").read_text()


class _NoCluster:
    def __enter__(self):
        return None

    def __exit__(self, *exc):
        return False


@pytest.mark.parametrize("argv, message", [
    (["--paper", "--camera"], "--paper and --camera are two sweeps: choose one"),
    (["--camera", "--width", "640", "--height", "480"],
     "--camera uses the camera formats' frames: drop --width/--height"),
])
def test_camera_bad_input_is_one_line(argv, message, capsys, tmp_path):
    assert main(["report", *argv, "--out", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err == f"npstereo: error: {message}\n"
    assert not (tmp_path / "out").exists()
