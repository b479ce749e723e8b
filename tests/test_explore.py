"""``npstereo explore``: a small grid on real Dask clusters (an embedded LocalCluster of two
worker processes, a separately launched ``dask scheduler`` and ``dask worker`` on the
loopback interface), a worker killed in the middle of a synthesis, the result cache, and
bad input.

The grid is two tiny cores (rank and census 3x3, D = 8, R = 2, 32 x 8) on the synthetic
scene: every synthesis takes seconds. Quality is checked against the golden model run
here, the memory bits against the architecture's formula, and every run against the
first one.
"""

import dataclasses
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import psutil
import pytest
from distributed import Client
from PIL import Image

from npstereo.gen.cli.cmd_explore import conditions, load_scenes
from npstereo.gen.cli.main import main
from npstereo.gen.explore import engine
from npstereo.gen.flow.capacity import DEVICES, fit_message, utilisation
from npstereo.gen.matching import match_images
from npstereo.gen.reports import synthesis
from npstereo.gen.explore.explorer import Grid, configurations, explore, pareto_front, plan_tasks, \
    recommend
from npstereo.golden.quality import evaluate
from npstereo.golden.synthetic import synthetic_pair
from npstereo.hdl import plan_memories, plan_timing
from npstereo.params import ParameterError, StereoParams, UserError

WIDTH, HEIGHT, DISPARITIES = 32, 8, 8
#: Worker processes of every cluster the tests start (marked ``dask``).
WORKERS = 2
GRID = ["--synthetic", "--transform", "rank", "census", "--block", "3", "--rounds", "2",
        "--disparities", str(DISPARITIES), "--width", str(WIDTH), "--height", str(HEIGHT),
        "--device", "cyclonev-a9", "--noise", "0.002"]
#: What must be equal between two runs of the grid (not times, not cache marks).
SYNTHESIS_FIGURES = ("status", "logic", "registers", "block_rams", "lut_rams", "memory_bits",
                     "logic_levels")
QUALITY_FIGURES = ("correct", "density", "error_rate", "evaluated")


def _grid_params():
    # The Cyclone V's six-input LUTs (rank and census have no sums of differences to
    # arrange: the same netlists as with four).
    return [StereoParams(transform=t, block=3, disparities=DISPARITIES, rounds=2,
                         width=WIDTH, height=HEIGHT, lut_inputs=6) for t in ("rank", "census")]


def _figures(document):
    """The numbers of every point, comparable between runs."""
    return [{"params": p["params"], "verdict": p["verdict"], "pareto": p["pareto"],
             "synthesis": {k: p["synthesis"].get(k) for k in SYNTHESIS_FIGURES},
             "quality": {label: {k: q.get(k) for k in QUALITY_FIGURES}
                         for label, q in p["quality"].items()}}
            for p in document["points"]]


@pytest.fixture(scope="module")
def first_run(tmp_path_factory):
    """The grid on an embedded LocalCluster of 2 workers, then again from its cache."""
    folder = tmp_path_factory.mktemp("explore")
    cache = folder / "cache"
    argv = ["explore", *GRID, "--workers", str(WORKERS), "--cache", str(cache)]
    assert main([*argv, "--out", str(folder / "one")]) == 0
    assert main([*argv, "--out", str(folder / "two")]) == 0
    load = lambda name: json.loads((folder / name / "explore.json").read_text())
    return folder, load("one"), load("two")


@pytest.mark.dask
def test_small_grid_quality_is_the_golden_models(first_run):
    _, document, _ = first_run
    pair = synthetic_pair(WIDTH, HEIGHT, DISPARITIES, seed=0)
    scenes = load_scenes(pair, conditions(0.002, False, 0))
    assert document["conditions"] == ["clean", "noise 0.002"]
    qualities = set()
    for params, point in zip(_grid_params(), document["points"]):
        assert point["params"]["transform"] == params.transform
        for label, (left, right, truth) in scenes.items():
            expected = evaluate(match_images(left, right, params), truth, DISPARITIES)
            measured = point["quality"][label]
            assert {k: measured[k] for k in QUALITY_FIGURES} == expected.as_dict()
            qualities.add(measured["correct"])
    assert len(qualities) > 1        # the transforms and conditions give different numbers


@pytest.mark.dask
def test_small_grid_synthesis_fit_and_ranking(first_run):
    _, document, _ = first_run
    dev = DEVICES["cyclonev-a9"]
    for params, point in zip(_grid_params(), document["points"]):
        result = point["synthesis"]
        assert result["status"] == "ok", result
        assert result["memory_bits"] == point["memory_bits"] == plan_memories.memory_bits(params)
        assert point["logic"] == result["logic"] + result["lut_rams"] > 0
        assert point["utilisation"] == utilisation(result, dev)
        assert point["fits"] is True and point["verdict"] == "fits"
        assert point["cycles_per_frame"] == plan_timing.cycles_per_frame(params)
        # No place and route: frames/s at the assumed 100 MHz.
        assert point["frames_per_second"] == pytest.approx(100e6 / point["cycles_per_frame"])
    points = document["points"]
    assert document["pareto"] == pareto_front(points) != []
    for i in document["pareto"]:       # nothing beats a point of the front
        assert not any(q["logic"] <= points[i]["logic"]
                       and q["quality"]["clean"]["correct"] > points[i]["quality"]["clean"]["correct"]
                       for q in points)
    best = max(points, key=lambda p: (p["quality"]["clean"]["correct"], -p["logic"]))
    assert points[document["recommendation"]] == best


@pytest.mark.dask
def test_small_grid_outputs(first_run):
    folder, document, _ = first_run
    text = (folder / "one" / "explore.md").read_text()
    assert "| rank 3x3 R=2 A=3 |" in text and "| census 3x3 R=2 A=3 |" in text
    assert "## Recommendation" in text and "5CEBA9" in text
    assert "Intel CV-51001" in text                      # the device table's references
    image = Image.open(folder / "one" / "pareto.png")
    assert image.size[0] > 600 and image.size[1] > 400
    assert not [p for p in (folder / "one").iterdir() if p.name.startswith(".")]


@pytest.mark.dask
def test_second_run_is_served_from_the_cache(first_run):
    _, first, second = first_run
    # The first run computed every evaluation: 2 syntheses, 2 x 2 quality measurements.
    assert first["tasks"]["submitted"] == len(first["tasks"]["computed"]) == 6
    assert second["tasks"]["submitted"] == 0 and second["tasks"]["computed"] == []
    assert all(p["synthesis"]["cached"] for p in second["points"])
    assert _figures(second) == _figures(first)


def _kill_first_synthesis(client, killed, stop):
    """Kill (SIGKILL) the first worker seen executing a synthesis, with its children."""
    while not stop.is_set():
        executing = client.run(engine._executing, on_error="ignore")
        pids = client.run(os.getpid, on_error="ignore")
        for address, keys in executing.items():
            if any(key.startswith("synthesis-") for key in keys) and address in pids:
                worker = psutil.Process(pids[address])
                for process in worker.children(recursive=True) + [worker]:
                    try:
                        process.send_signal(signal.SIGKILL)
                    except psutil.NoSuchProcess:
                        pass
                killed.update(address=address, pid=pids[address],
                              keys=[k for k in keys if k.startswith("synthesis-")])
                return
        time.sleep(0.05)


@pytest.mark.dask
def test_killed_worker_is_retried(first_run, tmp_path):
    """A worker killed in the middle of a synthesis: Dask gives the task to another worker
    and the explorer's results are complete and the same as an undisturbed run's."""
    _, reference, _ = first_run
    pair = synthetic_pair(WIDTH, HEIGHT, DISPARITIES, seed=0)
    scenes = load_scenes(pair, conditions(0.002, False, 0))
    killed, stop = {}, threading.Event()
    with engine.cluster(workers=WORKERS) as client:
        before = set(client.run(os.getpid).values())
        killer = threading.Thread(target=_kill_first_synthesis, args=(client, killed, stop))
        killer.start()
        try:
            result = explore(client, _grid_params(), scenes, "cyclonev-a9",
                             cache=tmp_path / "cache")
        finally:
            stop.set()
            killer.join()
        client.wait_for_workers(WORKERS, timeout=60)
        after = set(client.run(os.getpid).values())
    assert killed, "no synthesis was seen running"
    assert killed["pid"] not in after and after != before     # a new worker took its place
    assert result["tasks"]["failed"] == []
    assert len(result["tasks"]["computed"]) == 6
    document = dict(reference, **result)
    assert _figures(document) == _figures(reference)


def _free_port():
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.mark.dask
def test_separately_launched_scheduler_and_worker(first_run, tmp_path):
    """The same grid on a ``dask scheduler`` and a ``dask worker`` started apart (loopback
    only), with a cache of its own: the same results."""
    _, reference, _ = first_run
    address = f"tcp://127.0.0.1:{_free_port()}"
    scheduler = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
         "--port", address.rsplit(":", 1)[1], "--no-dashboard"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_worker", address, "--host", "127.0.0.1",
         "--nthreads", "1", "--nworkers", str(WORKERS), "--no-dashboard",
         "--memory-limit", "0"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        # The command gives a cluster 5 s to answer and 10 s to show a worker; starting
        # one on a loaded machine may take longer, and that is not what is tested here.
        with Client(address, timeout=120) as client:
            client.wait_for_workers(WORKERS, timeout=120)
        out = tmp_path / "out"
        assert main(["explore", *GRID, "--scheduler", address, "--cache",
                     str(tmp_path / "cache"), "--out", str(out)]) == 0
    finally:
        for process in (worker, scheduler):
            process.terminate()
        for process in (worker, scheduler):
            process.wait(timeout=30)
    document = json.loads((out / "explore.json").read_text())
    assert document["engine"] == f"the Dask scheduler at {address}"
    assert len(document["tasks"]["computed"]) == 6
    assert _figures(document) == _figures(reference)


def test_unreachable_scheduler_is_one_line_within_10_s(capsys, tmp_path):
    address = f"tcp://127.0.0.1:{_free_port()}"       # nothing listens there
    started = time.monotonic()
    assert main(["explore", *GRID, "--scheduler", address, "--cache", str(tmp_path / "c"),
                 "--out", str(tmp_path / "out")]) == 2
    assert time.monotonic() - started < 10
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and address in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("change, message", [
    ({"--device": "ecp5-12k"}, "argument --device: invalid choice: 'ecp5-12k'"),
    ({"--block": None}, "the grid is empty: --block has no values"),
    ({"--transform": None}, "the grid is empty: --transform has no values"),
    ({"--block": "4"}, "block size must be an odd integer >= 3, not 4"),
    ({"--rounds": "3"}, "rounds must divide disparities (8), not 3"),
    ({"--aggregation": "two"}, "aggregation must be an odd window size >= 1 or 'sgm', not 'two'"),
    ({"--pnr": True}, "--pnr places and routes ECP5 parts"),
    ({"--min-fps": "-1"}, "--min-fps must be a positive number"),
    ({"--workers": "0"}, "--workers must be an integer >= 1, not 0"),
    ({"--width": "8"}, "image width must be an integer > 8"),
    ({"--block": "33"}, "block size must be <= 31 for the hardware"),
    ({"--median": "maybe"}, "argument --median: invalid choice: 'maybe'"),
])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(change, message, capsys, tmp_path):
    argv = list(GRID)
    for option, value in change.items():
        if option in argv:
            index = argv.index(option) + 1
            end = next((i for i in range(index, len(argv)) if argv[i].startswith("--")),
                       len(argv))
            argv[index:end] = [] if value is None else [value]
        else:
            argv += [option] if value is True else [option, value]
    out, cache = tmp_path / "out", tmp_path / "cache"
    assert main(["explore", *argv, "--out", str(out), "--cache", str(cache)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err, err
    assert not out.exists() and not cache.exists()


def test_grid_order_and_aggregation_values_pass_through():
    grid = Grid(transforms=("rank", "census"), blocks=(3, 5), rounds=(1, 2),
                aggregations=(1, 3), line_buffers=("auto",), disparities=8, width=32,
                height=8)
    chosen, skipped = configurations(grid)
    assert len(chosen) == 16 and skipped == []
    assert chosen[0] == StereoParams(transform="rank", block=3, disparities=8, rounds=1,
                                     aggregation=1, width=32, height=8)
    # "sgm" is handed to StereoParams as given: the SGM core with its default penalties.
    sgm, skipped = configurations(Grid(("census",), (7,), (8,), ("sgm",), ("auto",), 16, 32, 8))
    assert skipped == [] and [p.aggregation for p in sgm] == ["sgm"] and sgm[0].p2 == 79
    # SGM's default P2 is too wide for census 3x3's costs, not for 7x7's: that one
    # combination is skipped and named, the rest of the grid runs.
    mixed, skipped = configurations(Grid(("census",), (3, 7), (8,), (3, "sgm"), ("auto",),
                                         8, 32, 8))
    assert [(p.block, p.aggregation) for p in mixed] == [(3, 3), (7, 3), (7, "sgm")]
    assert len(skipped) == 1 and skipped[0].startswith(
        "('census', 3, 8, 'sgm', 'auto', False, 0, False, None): P2")
    # A value that no combination takes is an error of its own.
    with pytest.raises(ParameterError, match="P2 must be <= 55"):
        configurations(Grid(("census",), (3,), (8,), (3, "sgm"), ("auto",), 8, 32, 8))


def test_cores_are_arranged_for_the_devices_luts():
    assert {name: d.lut_inputs for name, d in DEVICES.items()} == {
        "ecp5-85k": 4, "ecp5-45k": 4, "ecp5-25k": 4, "cyclonev-a9": 6, "ep2s180": 6}
    grid = Grid(("ext-census",), (3,), (2,), (3,), ("auto",), 8, 32, 8, lut_inputs=6)
    assert [p.lut_inputs for p in configurations(grid)[0]] == [6]


def _point(logic, correct, fits=True, fps=50.0, memory=100):
    return {"logic": logic, "quality": {"clean": {"correct": correct}}, "fits": fits,
            "frames_per_second": fps, "memory_bits": memory, "label": f"{logic}/{correct}"}


def test_pareto_front_and_recommendation():
    points = [_point(100, 80.0), _point(200, 90.0), _point(150, 70.0),  # dominated by 0
              _point(300, 95.0, fits=False), _point(250, 92.0, fps=10.0)]
    assert pareto_front(points) == [0, 1, 4, 3]
    assert recommend(points)[0] == 4                  # best that fits
    assert recommend(points, min_fps=30)[0] == 1      # 4 is too slow
    choice, reason = recommend(points, min_fps=100)
    assert choice is None and "100 frames/s" in reason


def test_fit_verdict_names_the_resource_on_each_device():
    big = {"logic": 158000, "registers": 1000, "block_rams": 10, "lut_rams": 0, "dsps": 0,
           "carry_chains": 0, "memory_bits": 10_000_000}
    assert utilisation(big, "ep2s180") == {"ALUT": 110.1, "FF": 0.7, "RAM bits": 106.6}
    assert fit_message(utilisation(big, "ep2s180")) == "does not fit (110 % ALUT, " \
                                                       "107 % RAM bits)"
    assert fit_message(utilisation(big, "cyclonev-a9")) is None
    assert fit_message(utilisation(big, "ecp5-85k")) == "does not fit (189 % LUT)"


def test_unreachable_scheduler_error_from_the_engine():
    with pytest.raises(UserError, match="no Dask scheduler answered within"):
        with engine.cluster(f"tcp://127.0.0.1:{_free_port()}"):
            pass


def test_ecp5_synthesis_is_shared_by_every_part_and_with_report(tmp_path):
    """Without place and route an ECP5 synthesis does not depend on the part: what the
    explorer synthesised for the 25k is cached as ``npstereo report --target ecp5`` would
    have it (checked against the 85k) and serves every part; with ``--pnr`` each part is
    placed on its own."""
    params = _grid_params()[0].replace(lut_inputs=DEVICES["ecp5-25k"].lut_inputs)
    cache = tmp_path / "cache"
    first = plan_tasks([params], {}, DEVICES["ecp5-25k"], False, 150.0, None, cache, None)
    [task] = first.tasks
    task.function(*task.args)                       # on this process: it fills the cache
    report = synthesis.lookup(params, ("ecp5",), False, 150.0, cache)["results"]["ecp5"]
    assert report["status"] == "ok" and "device" not in report
    assert report["utilisation"] == utilisation(report, "ecp5-85k")
    for name in ("ecp5-25k", "ecp5-45k", "ecp5-85k"):
        plan = plan_tasks([params], {}, DEVICES[name], False, 150.0, None, cache, None)
        assert plan.tasks == [] and plan.synthesis[0]["results"]["ecp5"] == report
    placed = plan_tasks([params], {}, DEVICES["ecp5-25k"], True, 150.0, None, cache, None)
    assert [task.args[-1] for task in placed.tasks] == ["ecp5-25k"]


@pytest.mark.parametrize("bits", ["6", "-1"])
def test_subpixel_bits_out_of_range_is_one_line(bits, capsys, tmp_path):
    out, cache = tmp_path / "out", tmp_path / "cache"
    assert main(["explore", *GRID, "--subpixel-bits", "0", bits, "--out", str(out),
                 "--cache", str(cache)]) == 2
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [
        f"npstereo: error: subpixel bits must be an integer 0 .. 5, not {bits}"]
    assert "Traceback" not in captured.err + captured.out
    assert not out.exists() and not cache.exists()
    assert main(["explore", *GRID, "--subpixel-bits", "--out", str(out), "--cache",
                 str(cache)]) == 2
    assert capsys.readouterr().err.splitlines() == [
        "npstereo: error: the grid is empty: --subpixel-bits has no values"]


def test_median_and_subpixel_axes():
    grid = Grid(("census",), (3,), (2,), (3,), ("auto",), 8, 32, 8, medians=(False, True),
                subpixel_bits=(0, 4))
    chosen, skipped = configurations(grid)
    assert skipped == [] and [(p.median, p.subpixel_bits) for p in chosen] == [
        (False, 0), (False, 4), (True, 0), (True, 4)]


def test_quality_scores_the_fraction():
    """With F = 4 the quality task scores the fractional disparities: the golden model's
    levels and their mean error over the correct pixels, which the same map rounded to
    whole levels (a fraction dropped before scoring) does not give."""
    from npstereo.gen.explore.explorer import quality_task
    from npstereo.golden.quality import mean_absolute_error
    pair = synthetic_pair(64, 24, 16, seed=0)
    left, right = pair.gray()
    for bits in (0, 4):
        params = StereoParams(transform="census", block=5, disparities=16, subpixel_bits=bits)
        result = quality_task((left, right, pair.ground_truth), params, None, "k")
        disparity = match_images(left, right, params)
        assert (disparity.dtype.kind == "f") == (bits > 0)
        expected = evaluate(disparity, pair.ground_truth, 16).as_dict()
        assert {k: result[k] for k in QUALITY_FIGURES} == expected
        error = mean_absolute_error(disparity, pair.ground_truth, 16)
        assert result["mean_error"] == round(error, 4)
    rounded = np.where(disparity >= 0, np.round(disparity), -1)
    assert round(mean_absolute_error(rounded, pair.ground_truth, 16), 4) != result["mean_error"]


@pytest.mark.dask
def test_explore_with_median_and_fraction(capsys, tmp_path):
    """One core with the median and F = 4 through the whole command: its label, its
    parameters in explore.json and its row with the mean error in explore.md."""
    argv = ["explore", "--synthetic", "--transform", "census", "--block", "3", "--rounds",
            "2", "--disparities", str(DISPARITIES), "--width", str(WIDTH), "--height",
            str(HEIGHT), "--device", "cyclonev-a9", "--median", "--subpixel-bits", "4",
            "--workers", "1", "--cache", str(tmp_path / "cache"), "--out", str(tmp_path / "o")]
    assert main(argv) == 0
    document = json.loads((tmp_path / "o" / "explore.json").read_text())
    (point,) = document["points"]
    assert point["params"]["median"] is True and point["params"]["subpixel_bits"] == 4
    assert point["label"] == "census 3x3 R=2 A=3 median F=4"
    assert point["synthesis"]["status"] == "ok"
    params = StereoParams(transform="census", block=3, disparities=DISPARITIES, rounds=2,
                          median=True, subpixel_bits=4)
    pair = synthetic_pair(WIDTH, HEIGHT, DISPARITIES, seed=0)
    left, right = pair.gray()
    expected = evaluate(match_images(left, right, params), pair.ground_truth, DISPARITIES)
    assert {k: point["quality"]["clean"][k] for k in QUALITY_FIGURES} == expected.as_dict()
    text = (tmp_path / "o" / "explore.md").read_text()
    row = next(line for line in text.splitlines() if line.startswith("| census 3x3 R=2 A=3 median F=4 |"))
    assert f"| {point['quality']['clean']['mean_error']:,.3f} |" in row


def test_plot_labels_name_the_varying_output_options():
    from npstereo.gen.cli.cmd_explore import _on_off, _short_labels
    assert (_on_off(None), _on_off([]), _on_off(["off", "on"])) == (
        (False,), (True,), (False, True))
    chosen, _ = configurations(Grid(("census",), (3,), (2,), (3,), ("auto",), 8, 32, 8,
                                    medians=(False, True), subpixel_bits=(0, 4)))
    points = [{"params": dataclasses.asdict(p)} for p in chosen]
    assert _short_labels(points) == ["census 3 no median F=0", "census 3 no median F=4",
                                     "census 3 median F=0", "census 3 median F=4"]


def test_plot_of_a_grid_whose_every_synthesis_failed(tmp_path):
    """No point has logic (every synthesis failed or timed out): the plot is still drawn,
    with the device's capacity and no points (an empty ``fits`` was a float array, and its
    negation a TypeError)."""
    from npstereo.gen.reports.plots import pareto_plot
    points = [{"logic": None, "memory_bits": 1000, "fits": None, "logic_levels": None,
               "quality": {"clean": {"correct": 50.0}}}]
    path = tmp_path / "pareto.png"
    pareto_plot(path, points, ["rank 3"], [], None, DEVICES["cyclonev-a9"], "logic_levels",
                "LUT levels", "every synthesis failed")
    assert Image.open(path).size[0] > 600

