"""The whole core in Amaranth's simulator against the golden model, every output pixel.

Frames are small (the Python simulator runs a few thousand clocks per second); the matrix
covers all four transforms, block sizes 3/5/7, D in {8, 16}, R in {1, 2, 4}, the L/R check
on and off, aggregation 1/3/5, with random source gaps and sink backpressure of 35 % each.
Scenario tests cover back-to-back frames, a reset in mid-frame, mis-framed input and the
throughput; ``test_broken_*`` prove that the comparison catches a wrong tie rule.
"""

import numpy as np
import pytest

from npstereo.golden.params import StereoParams
from npstereo.golden.pipeline import disparity_map
from npstereo.hdl import trees
from npstereo.hdl.core import NpStereoCore

from hdl_helpers import RESET, decode_frames, first_mismatch, frame_beats, run_scenario

GAPS = 0.65  # probability that the source offers / the sink takes: >= 30 % stalls each


def random_pair(rng, width, height):
    return (rng.integers(0, 256, (height, width), dtype=np.uint8),
            rng.integers(0, 256, (height, width), dtype=np.uint8))


def scene_pair(rng, width, height, disparities):
    """A textured plane, a nearer textured rectangle and a flat band (ties galore).

    The right view is the left one shifted by each layer's disparity; the flat band makes
    many disparities cost the same, which is where the tie rule shows.
    """
    texture = rng.integers(0, 256, (height, width + disparities), dtype=np.uint8)
    near = rng.integers(0, 256, (height, width + disparities), dtype=np.uint8)
    far_d, near_d = disparities // 4, disparities - 2
    right = texture[:, :width].copy()
    left = texture[:, far_d:far_d + width].copy()
    y0, y1, x0, x1 = height // 4, 3 * height // 4, width // 2, width - 2
    left[y0:y1, x0:x1] = near[y0:y1, x0:x1]
    right[y0:y1, x0 - near_d:x1 - near_d] = near[y0:y1, x0:x1]
    left[-4:, :], right[-4:, :] = 90, 90
    return left, right


def check_frames(params, pairs, beats, **kwargs):
    """Run ``beats``; compare the last len(pairs) output frames with the golden maps."""
    result = run_scenario(params, beats, **kwargs)
    frames = decode_frames(result["words"], params)
    assert len(frames) >= len(pairs), f"only {len(frames)} output frames"
    for n, ((left, right), got) in enumerate(zip(pairs, frames[-len(pairs):])):
        expected = disparity_map(left, right, params).disparity
        mismatch = first_mismatch(expected, got)
        assert mismatch is None, f"frame {n} of {params.describe()}: {mismatch}"
    return result


MATRIX = [
    # transform, block, D, R, A, lr, image
    ("census", 3, 8, 1, 3, 1, "random"),
    ("census", 5, 16, 4, 3, 2, "scene"),
    ("census", 7, 8, 2, 3, None, "scene"),
    ("rank", 3, 8, 2, 3, None, "random"),
    ("rank", 5, 8, 1, 3, 0, "scene"),
    ("rank", 7, 16, 2, 3, 1, "random"),
    ("ext-rank", 3, 8, 4, 3, 1, "scene"),
    ("ext-rank", 5, 16, 1, 5, None, "random"),
    ("ext-census", 3, 16, 2, 1, 1, "random"),
    ("ext-census", 5, 8, 4, 3, None, "scene"),
    ("census", 3, 12, 3, 3, 1, "scene"),  # D not a power of two
]


@pytest.mark.parametrize("transform,block,disparities,rounds,aggregation,lr,image", MATRIX)
def test_matches_golden(transform, block, disparities, rounds, aggregation, lr, image):
    width, height = disparities + 12, 8
    params = StereoParams(transform=transform, block=block, disparities=disparities,
                          rounds=rounds, aggregation=aggregation, lr_threshold=lr,
                          width=width, height=height)
    rng = np.random.default_rng(block * 100 + disparities + rounds)
    pair = (random_pair(rng, width, height) if image == "random"
            else scene_pair(rng, width, height, disparities))
    check_frames(params, [pair], frame_beats(*pair), valid_prob=GAPS, ready_prob=GAPS,
                 seed=rounds)


def test_two_frames_back_to_back():
    params = StereoParams(transform="census", block=5, disparities=8, rounds=2,
                          lr_threshold=1, width=20, height=7)
    rng = np.random.default_rng(7)
    pairs = [scene_pair(rng, 20, 7, 8), random_pair(rng, 20, 7)]
    result = check_frames(params, pairs, frame_beats(*pairs[0]) + frame_beats(*pairs[1]),
                          valid_prob=GAPS, ready_prob=GAPS, seed=3)
    assert result["errors"] == 0


def test_reset_mid_frame_then_clean_frame():
    params = StereoParams(transform="rank", block=3, disparities=8, rounds=2,
                          lr_threshold=1, width=18, height=6)
    rng = np.random.default_rng(11)
    first, second = random_pair(rng, 18, 6), scene_pair(rng, 18, 6, 8)
    beats = frame_beats(*first)[:50] + [RESET] + frame_beats(*second)
    check_frames(params, [second], beats, valid_prob=GAPS, ready_prob=GAPS, seed=5)


@pytest.mark.parametrize("fault", ["long line", "short line", "no start of frame",
                                   "early start of frame"])
def test_misframed_input_then_clean_frame(fault):
    width, height = 18, 6
    params = StereoParams(transform="census", block=3, disparities=8, rounds=1,
                          lr_threshold=1, width=width, height=height)
    rng = np.random.default_rng(13)
    bad, good = random_pair(rng, width, height), scene_pair(rng, width, height, 8)
    if fault == "long line":
        broken = frame_beats(*bad, drop_last_at=2)
    elif fault == "short line":
        broken = frame_beats(*bad)
        data, user, _ = broken[width + 5]
        broken[width + 5] = (data, user, True)
    elif fault == "no start of frame":
        broken = frame_beats(*bad)[1:]
    else:
        broken = frame_beats(*bad)[:40]  # the next frame starts inside this one
    result = check_frames(params, [good], broken + frame_beats(*good),
                          valid_prob=GAPS, ready_prob=GAPS, seed=2)
    assert result["errors"] >= 1


def test_no_error_on_clean_input():
    params = StereoParams(transform="census", block=3, disparities=8, rounds=1,
                          width=12, height=4)
    pair = random_pair(np.random.default_rng(1), 12, 4)
    result = check_frames(params, [pair, pair], frame_beats(*pair) * 2)
    assert result["errors"] == 0


@pytest.mark.parametrize("rounds", [1, 4])
def test_throughput(rounds):
    """Frame period without stalls: W*H*R clocks plus the flush of the pipeline latency."""
    width, height = 32, 16
    params = StereoParams(transform="census", block=3, disparities=8, rounds=rounds,
                          lr_threshold=1, width=width, height=height)
    pair = random_pair(np.random.default_rng(2), width, height)
    result = check_frames(params, [pair, pair], frame_beats(*pair) * 2)
    period = result["frame_starts"][-1] - result["frame_starts"][-2]
    bound = 1.01 * width * height * rounds + result["latency"] * rounds
    print(f"R={rounds}: {period} clocks per {width}x{height} frame "
          f"({period / (width * height * rounds):.3f} x W*H*R), latency "
          f"{result['latency']} pixels")
    assert period <= bound


def test_broken_tie_rule_is_caught(monkeypatch):
    """Ties to the highest disparity in the partition WTA must be detected."""
    monkeypatch.setattr(trees, "_takes_upper", lambda lower, upper: upper <= lower)
    params = StereoParams(transform="census", block=3, disparities=8, rounds=2,
                          lr_threshold=None, width=20, height=8)
    pair = scene_pair(np.random.default_rng(3), 20, 8, 8)
    with pytest.raises(AssertionError, match="pixels differ"):
        check_frames(params, [pair], frame_beats(*pair))


def test_broken_evaluation_comparison_is_caught(monkeypatch):
    """Across partitions, equal costs going to the later partition (not the lower
    disparity) is detected."""
    from npstereo.hdl import evaluation_stage
    bits = StereoParams(disparities=8).disparity_bits
    monkeypatch.setattr(evaluation_stage, "_better",
                        lambda candidate, best: candidate[bits:] <= best[bits:])
    params = StereoParams(transform="census", block=3, disparities=8, rounds=4,
                          lr_threshold=None, width=20, height=8)
    pair = scene_pair(np.random.default_rng(3), 20, 8, 8)
    with pytest.raises(AssertionError, match="pixels differ"):
        check_frames(params, [pair], frame_beats(*pair))


def test_missing_size_is_a_parameter_error():
    from npstereo.golden.params import ParameterError
    with pytest.raises(ParameterError, match="width and height"):
        NpStereoCore(StereoParams(transform="census", block=3, disparities=8))


def test_broken_credit_is_caught(monkeypatch):
    """Admission that ignores the output queue's room loses words under backpressure."""
    from npstereo.hdl import core as core_module
    monkeypatch.setattr(core_module, "_has_room", lambda credits: 1)
    params = StereoParams(transform="census", block=3, disparities=8, rounds=1,
                          lr_threshold=None, width=20, height=8)
    pair = scene_pair(np.random.default_rng(3), 20, 8, 8)
    with pytest.raises(AssertionError, match="pixels differ|output frames"):
        check_frames(params, [pair], frame_beats(*pair), valid_prob=1.0, ready_prob=0.3)
