"""The golden SGM aggregation (golden/sgm.py) against a plain per-pixel reference.

The reference below is written straight from docs/semantics.md ("Semi-global aggregation")
with Python loops over pixels and
disparities on Python integers (no numpy arithmetic, no shifts: divisions by powers of two,
a brute-force bit length); it shares no code with golden/sgm.py. The matching costs come from
tests/reference.py, the box pipeline's independent reference, with the SGM rule for
x - d < 0 applied here. Images are tiny and made to produce ties and extreme costs.

Every ``test_broken_*`` case breaks one rule of the golden model (monkeypatch) and asserts
that the comparison with the reference now fails, so each comparison is shown to be able to
fail.
"""

import itertools

import numpy as np
import pytest

from npstereo.golden import pipeline, sgm
from npstereo.params import (SGM_DEFAULT_P1, SGM_DEFAULT_P2, SGM_PATH_STEPS, SGM_PATHS,
                             SGM_RECOMMENDED, TRANSFORMS, ParameterError, StereoParams,
                             check_penalties, check_sgm_paths, max_path_penalty,
                             sgm_left_cost_bits, sgm_left_loop_bits, sgm_path_cost_bits,
                             sgm_path_steps, sgm_summed_cost_bits)

import reference

# Reference ---------------------------------------------------------------------------------

#: Predecessor offsets, written out again (not imported) so a wrong table in the golden
#: model cannot agree with itself.
REF_STEPS = {"left": (-1, 0), "top-left": (-1, -1), "top": (0, -1), "top-right": (1, -1)}
#: The left path's tracking constants J and K, and the parity of the columns its small step
#: goes into, written out again for the same reason.
REF_J, REF_K, REF_P1_PARITY = 8, 32, 1


def ref_bit_length(value):
    """Smallest n with value < 2^n (0 for 0), by counting."""
    n = 0
    while 2 ** n <= value:
        n += 1
    return n


def ref_costs(left, right, name, block, disparities):
    """C[y][x][d] for SGM: the box reference's costs, Cmax where x - d < 0."""
    volume = reference.cost_volume(left, right, name, block, disparities)
    cmax = StereoParams(transform=name, block=block).max_cost
    return [[[cmax if x - d < 0 else volume[y][x][d] for d in range(disparities)]
             for x in range(len(volume[0]))] for y in range(len(volume))]


def ref_p2(image, x, y, px, py, p1, p2, adapt):
    """P2 at (x, y) coming from (px, py): constant, or P2 / 2^s floored, at least P1."""
    if adapt is None:
        return p2
    step = abs(int(image[y][x]) - int(image[py][px]))
    s = max(0, ref_bit_length(step) - adapt)
    return max(p1, p2 // 2 ** s)


def ref_path(costs, path, p1, p2, image=None, adapt=None):
    """L_r[y][x][d] of one path, visiting pixels in raster order."""
    if path == "left":
        return [ref_left_row(row, p1, [ref_p2(image, x, y, x - 1, y, p1, p2, adapt)
                                       if x else p2 for x in range(len(row))])
                for y, row in enumerate(costs)]
    height, width, disparities = len(costs), len(costs[0]), len(costs[0][0])
    dx, dy = REF_STEPS[path]
    out = [[None] * width for _ in range(height)]
    for y in range(height):
        for x in range(width):
            px, py = x + dx, y + dy
            here = [int(c) for c in costs[y][x]]
            if not (0 <= px < width and 0 <= py < height):
                out[y][x] = here  # the path starts fresh at the border
                continue
            previous = out[py][px]
            low = min(previous)
            penalty2 = ref_p2(image, x, y, px, py, p1, p2, adapt)
            row = []
            for d in range(disparities):
                candidates = [previous[d], low + penalty2]
                if d > 0:
                    candidates.append(previous[d - 1] + p1)
                if d < disparities - 1:
                    candidates.append(previous[d + 1] + p1)
                row.append(here[d] + min(candidates) - low)
            out[y][x] = row
    return out


def ref_tracked(unnormalised, costs, x):
    """ref(x) of the left path: Lu(s, b) + C(s+1, b) + ... + C(x-1, b) with s = max(x-J, 0)
    and b the lowest d of the smallest Lu(max(x-K, 0), d)."""
    old = unnormalised[max(x - REF_K, 0)]
    b = old.index(min(old))
    s = max(x - REF_J, 0)
    return unnormalised[s][b] + sum(costs[i][b] for i in range(s + 1, x))


def ref_left_row(costs, p1, penalties, reference=ref_tracked):
    """The left path of one row: unnormalised Lu in Python integers, then L(x, d) =
    Lu(x, d) - min_d Lu(x-1, d). ``penalties[x]`` is P2(x); ``reference(Lu, C, x)`` the
    reference of the large step."""
    costs = [[int(c) for c in column] for column in costs]
    disparities = len(costs[0])
    lu = [costs[0]]
    for x in range(1, len(costs)):
        previous, ref = lu[x - 1], reference(lu, costs, x)
        column = []
        for d in range(disparities):
            candidates = [previous[d], ref + penalties[x]]
            if d > 0 and x % 2 == REF_P1_PARITY:
                candidates.append(previous[d - 1] + p1)
            if d < disparities - 1 and x % 2 == REF_P1_PARITY:
                candidates.append(previous[d + 1] + p1)
            column.append(costs[x][d] + min(candidates))
        lu.append(column)
    return [lu[0]] + [[value - min(lu[x - 1]) for value in lu[x]] for x in range(1, len(lu))]


def ref_summed(costs, paths, p1, p2, image=None, adapt=None):
    parts = [ref_path(costs, path, p1, p2, image, adapt) for path in paths]
    return [[[sum(part[y][x][d] for part in parts) for d in range(len(costs[0][0]))]
             for x in range(len(costs[0]))] for y in range(len(costs))]


def ref_map(left, right, name, block, disparities, p1, p2, paths, adapt, threshold):
    costs = ref_costs(left, right, name, block, disparities)
    summed = ref_summed(costs, paths, p1, p2, left, adapt)
    # Aggregation size 1 makes the box reference's border x < D, the SGM border.
    return reference.disparity_from_aggregated(summed, 1, threshold)


# Inputs -------------------------------------------------------------------------------------


def make_pair(kind, height, width, seed):
    """Left image and a right image mostly shifted by 1-3 columns, with 10 % noise.

    ``random`` bytes, ``levels`` (3 gray levels: many equal costs), ``saturated`` (0/255:
    extreme costs and intensity steps), ``ramp`` (steps of every size for adaptive P2).
    """
    rng = np.random.default_rng(seed)
    if kind == "random":
        left = rng.integers(0, 256, (height, width))
    elif kind == "levels":
        left = rng.choice([0, 100, 101], (height, width))
    elif kind == "saturated":
        left = rng.choice([0, 255], (height, width))
    elif kind == "ramp":
        left = (np.arange(width)[None, :] * rng.integers(1, 40, (height, 1))) % 256
    else:
        raise ValueError(kind)
    shift = rng.integers(1, 4, height)[:, None]
    columns = np.clip(np.arange(width)[None, :] + shift, 0, width - 1)
    right = np.take_along_axis(left, columns, axis=1)
    noise = rng.random((height, width)) < 0.1
    right = np.where(noise, rng.integers(0, 256, (height, width)), right)
    return left.astype(np.uint8), right.astype(np.uint8)


def as_array(nested):
    return np.array(nested, dtype=np.int64)


def golden_path(costs, path, p1, p2, image=None, adapt=None, max_cost=None):
    volume = np.asarray(costs, dtype=np.uint32)
    return sgm.path_costs(volume, path, p1, p2, guide=image, adapt=adapt,
                          max_cost=max_cost).astype(np.int64)


def random_volume(rng, height, width, disparities, cmax, extreme=False):
    if extreme:
        return rng.choice([0, cmax], (height, width, disparities))
    return rng.integers(0, cmax + 1, (height, width, disparities))


# Cost volume -------------------------------------------------------------------------------


@pytest.mark.parametrize("name", TRANSFORMS)
def test_cost_volume_matches_reference(name):
    left, right = make_pair("levels", 6, 13, 3)
    block = 3 if name.startswith("ext") else 5
    params = StereoParams(transform=name, block=block, disparities=7)
    expected = as_array(ref_costs(left, right, name, block, 7))
    assert np.array_equal(sgm.cost_volume(left, right, params).astype(np.int64), expected)


def test_cost_volume_is_cmax_where_no_partner():
    left, right = make_pair("random", 5, 12, 0)
    params = StereoParams(transform="census", block=3, disparities=6)
    volume = sgm.cost_volume(left, right, params)
    for d in range(6):
        assert (volume[:, :d, d] == params.max_cost).all()
    # Counterpart: with a partner the cost is the ordinary one, mostly below Cmax.
    assert (volume[:, 6:, :] < params.max_cost).any()


# Single paths and their combinations -------------------------------------------------------


@pytest.mark.parametrize("path", SGM_PATHS)
@pytest.mark.parametrize("p1, p2", [(0, 0), (1, 3), (3, 7), (2, 40), (5, 5)])
def test_each_path_matches_reference(path, p1, p2):
    # A seed fixed per case (hash() of a string changes from run to run).
    rng = np.random.default_rng([SGM_PATHS.index(path), p1, p2])
    costs = random_volume(rng, 6, 9, 5, 8)
    expected = as_array(ref_path(costs.tolist(), path, p1, p2))
    assert np.array_equal(golden_path(costs, path, p1, p2, max_cost=8), expected)


@pytest.mark.parametrize("path", SGM_PATHS)
@pytest.mark.parametrize("adapt", [1, 2, 4, 7])
def test_each_path_with_adaptive_p2_matches_reference(path, adapt):
    left, _ = make_pair("ramp", 6, 11, adapt)
    rng = np.random.default_rng(adapt)
    costs = random_volume(rng, 6, 11, 6, 24)
    expected = as_array(ref_path(costs.tolist(), path, 3, 96, left, adapt))
    assert np.array_equal(golden_path(costs, path, 3, 96, left, adapt, max_cost=24), expected)


@pytest.mark.parametrize("count", [1, 2, 3, 4])
def test_path_combinations_match_reference(count):
    rng = np.random.default_rng(count)
    costs = random_volume(rng, 5, 8, 4, 24)
    image = rng.integers(0, 256, (5, 8)).astype(np.uint8)
    for paths in itertools.combinations(SGM_PATHS, count):
        expected = as_array(ref_summed(costs.tolist(), paths, 2, 30, image, 3))
        summed = sgm.aggregate(costs.astype(np.uint16), 2, 30, paths, guide=image, adapt=3,
                               max_cost=24)
        assert np.array_equal(summed.astype(np.int64), expected), paths


def test_threads_do_not_change_the_sum():
    rng = np.random.default_rng(5)
    costs = random_volume(rng, 7, 12, 6, 24).astype(np.uint16)
    one = sgm.aggregate(costs, 4, 50, threads=1)
    assert np.array_equal(one, sgm.aggregate(costs, 4, 50, threads=4))


# Whole maps ---------------------------------------------------------------------------------


MAP_CASES = [
    # name, block, D, kind, p1, p2, adapt, thresholds
    ("census", 5, 6, "levels", 4, 20, None, (None, 0, 3)),
    ("census", 3, 5, "random", 2, 8, 3, (None, 1)),
    ("rank", 3, 4, "saturated", 1, 9, 2, (None, 0)),
    ("ext-rank", 3, 5, "ramp", 100, 3000, 4, (3,)),
    ("ext-census", 3, 4, "random", 200, 1000, None, (1,)),
    ("census", 5, 8, "ramp", 6, 60, 5, (None, 2)),
]


@pytest.mark.parametrize("name, block, D, kind, p1, p2, adapt, thresholds", MAP_CASES)
def test_disparity_map_matches_reference(name, block, D, kind, p1, p2, adapt, thresholds):
    left, right = make_pair(kind, 7, D + 9, D)
    for threshold in thresholds:
        expected = ref_map(left, right, name, block, D, p1, p2, SGM_PATHS, adapt, threshold)
        for rounds in (1, D):  # R does not change the result
            params = StereoParams(transform=name, block=block, disparities=D, rounds=rounds,
                                  lr_threshold=threshold)
            result = sgm.disparity_map(left, right, params, p1, p2, adapt=adapt, threads=2)
            assert np.array_equal(result.disparity, expected), (threshold, rounds)


@pytest.mark.parametrize("band_rows", [1, 2, 3])
def test_disparity_map_band_seams(monkeypatch, band_rows):
    """Bands of 1-3 rows: the paths from above carry their last row across each seam."""
    name, block, D, kind, p1, p2, adapt, _ = MAP_CASES[1]
    left, right = make_pair(kind, 7, D + 9, D)
    monkeypatch.setattr(sgm, "_BAND_ELEMENTS", band_rows * (D + 9) * D)
    expected = ref_map(left, right, name, block, D, p1, p2, SGM_PATHS, adapt, 1)
    params = StereoParams(transform=name, block=block, disparities=D, lr_threshold=1)
    result = sgm.disparity_map(left, right, params, p1, p2, adapt=adapt, threads=3)
    assert np.array_equal(result.disparity, expected)
    whole = sgm.disparity_from_summed(
        sgm.aggregate(sgm.cost_volume(left, right, params), p1, p2, guide=left, adapt=adapt,
                      max_cost=params.max_cost), 1)
    assert np.array_equal(result.left, whole.left) and np.array_equal(result.right, whole.right)


def test_broken_band_seam_is_caught(monkeypatch):
    # Paths from above that start fresh at every band instead of carrying the row above.
    original = sgm._row_band
    monkeypatch.setattr(sgm, "_row_band", lambda costs, dx, p1, p2_map, previous, out:
                        original(costs, dx, p1, p2_map, None, out))
    monkeypatch.setattr(sgm, "_BAND_ELEMENTS", 1)
    name, block, D, kind, p1, p2, adapt, _ = MAP_CASES[1]
    left, right = make_pair(kind, 7, D + 9, D)
    params = StereoParams(transform=name, block=block, disparities=D, lr_threshold=None)
    expected = ref_map(left, right, name, block, D, p1, p2, SGM_PATHS, adapt, None)
    result = sgm.disparity_map(left, right, params, p1, p2, adapt=adapt)
    assert not np.array_equal(result.disparity, expected)


def test_disparity_map_keeps_and_rejects():
    # Counterpart of the map comparison: the case has both kept and invalid pixels beyond
    # the border, so an all-invalid or all-kept map could not pass it.
    left, right = make_pair("random", 7, 15, 6)
    expected = ref_map(left, right, "census", 5, 6, 4, 20, SGM_PATHS, None, 0)
    assert (expected[:, 6:] >= 0).any() and (expected[:, 6:] < 0).any()
    assert (expected[:, :6] < 0).all()


# Borders -------------------------------------------------------------------------------------

#: Pixels whose predecessor is outside the frame, per path, for an H x W frame.
START = {
    "left": lambda y, x, h, w: x == 0,
    "top-left": lambda y, x, h, w: x == 0 or y == 0,
    "top": lambda y, x, h, w: y == 0,
    "top-right": lambda y, x, h, w: y == 0 or x == w - 1,
}


@pytest.mark.parametrize("path", SGM_PATHS)
def test_paths_start_fresh_at_the_border(path):
    rng = np.random.default_rng(11)
    costs = random_volume(rng, 5, 7, 4, 24)
    out = golden_path(costs, path, 3, 30, max_cost=24)
    for y, x in itertools.product(range(5), range(7)):
        if START[path](y, x, 5, 7):
            assert np.array_equal(out[y, x], costs[y, x]), (y, x)
    # Counterpart: elsewhere the path does add something (the check can see a difference).
    inner = [(y, x) for y, x in itertools.product(range(5), range(7))
             if not START[path](y, x, 5, 7)]
    assert any(not np.array_equal(out[y, x], costs[y, x]) for y, x in inner)


def test_frame_of_one_row_and_one_column():
    rng = np.random.default_rng(2)
    for shape in ((1, 9, 5), (6, 1, 5), (1, 1, 3)):
        costs = random_volume(rng, *shape, 24)
        for path in SGM_PATHS:
            expected = as_array(ref_path(costs.tolist(), path, 2, 10))
            assert np.array_equal(golden_path(costs, path, 2, 10, max_cost=24), expected)


# The left path's reference ----------------------------------------------------------------------

LEFT_CASES = [
    # height, width, D, Cmax, P1, P2, costs drawn from
    (3, 72, 5, 24, 3, 20, "random"),
    (4, 69, 6, 3, 1, 2, "levels"),       # costs 0 .. 3: ties everywhere, argmin ties too
    (2, 77, 1, 24, 0, 0, "random"),      # one disparity
    (3, 65, 8, 48, 24, 79, "extreme"),   # costs 0 and Cmax only
]


def left_volume(rng, height, width, disparities, cmax, kind):
    if kind == "levels":
        return rng.integers(0, cmax + 1, (height, width, disparities))
    return random_volume(rng, height, width, disparities, cmax, extreme=kind == "extreme")


@pytest.mark.parametrize("height, width, D, cmax, p1, p2, kind", LEFT_CASES)
def test_left_path_tracks_the_best_disparity(height, width, D, cmax, p1, p2, kind):
    """Rows longer than K, so that b comes from x - K and the sum from x - J."""
    costs = left_volume(np.random.default_rng(width), height, width, D, cmax, kind)
    expected = as_array(ref_path(costs.tolist(), "left", p1, p2))
    assert np.array_equal(golden_path(costs, "left", p1, p2, max_cost=cmax), expected)
    # The tracked reference is not the exact minimum: the comparison can tell them apart.
    exact = as_array([ref_left_row(row, p1, [p2] * width, lambda lu, c, x: min(lu[x - 1]))
                      for row in costs.tolist()])
    assert D == 1 or not np.array_equal(exact, expected)


def exact_reference(path, costs, best, x, index):
    """Exact SGM's reference, min_d Lu(x - 1, d), in the golden model's signature."""
    return path[x - 1].min(axis=1)


@pytest.mark.parametrize("height, width, D, cmax, p1, p2, kind", LEFT_CASES)
def test_left_path_with_the_exact_minimum_is_exact_sgm(monkeypatch, height, width, D, cmax,
                                                       p1, p2, kind):
    """With ref(x) = min_d Lu(x-1, d) the left path is SGM's recurrence with the small step
    into the columns of one parity only: the unnormalised recurrence with the exact minimum,
    normalised afterwards (the normalisation commutes with the minimum)."""
    costs = left_volume(np.random.default_rng(D), height, width, D, cmax, kind)
    exact = as_array([ref_left_row(row, p1, [p2] * width, lambda lu, c, x: min(lu[x - 1]))
                      for row in costs.tolist()])
    monkeypatch.setattr(sgm, "_tracked_reference", exact_reference)
    assert np.array_equal(golden_path(costs, "left", p1, p2, max_cost=cmax), exact)


def left_width_violations(seed):
    """Left path values outside 0 .. K Cmax + P2 over random volumes (none allowed)."""
    found = 0
    for k, (cmax, p1, p2) in enumerate([(24, 1, 2), (48, 24, 79), (8, 0, 0), (24, 12, 103)]):
        rng = np.random.default_rng(seed + k)
        for kind in ("random", "extreme", "levels"):
            costs = left_volume(rng, 4, 60, 6, cmax, kind)
            got = golden_path(costs, "left", p1, p2, max_cost=cmax)
            # A negative L wraps above the bound in the golden model's unsigned dtype.
            found += int(np.count_nonzero(got > REF_K * cmax + p2))
    return found


def test_left_path_widths_hold():
    assert left_width_violations(seed=5) == 0


def test_broken_stale_minimum_breaks_the_widths(monkeypatch):
    """The minimum of K positions back as the reference (no tracking): it falls behind
    m(x - 1) and L leaves its range."""
    def stale(path, costs, best, x, index):
        return path[max(x - REF_K, 0)].min(axis=1)
    monkeypatch.setattr(sgm, "_tracked_reference", stale)
    assert left_width_violations(seed=5) > 0


# Widths ---------------------------------------------------------------------------------------


def test_widths_formulae():
    # Census 5x5, P2 = 64: L of the left path <= 32 x 24 + 64 = 832 (10 bits), S <= 832 +
    # 3 x 88 = 1096 (11 bits); modulo 2^n with 2^(n-1) > 832 + 24 + P1.
    assert (sgm_path_cost_bits(24, 64), sgm_left_cost_bits(24, 64),
            sgm_summed_cost_bits(24, 64)) == (7, 10, 11)
    assert sgm_left_loop_bits(24, 167, 64) == 11 and sgm_left_loop_bits(24, 168, 64) == 12
    assert max_path_penalty(24) == 103 and sgm_path_cost_bits(24, 103) == 7
    assert sgm_path_cost_bits(80, 47) == 7 and sgm_path_cost_bits(80, 48) == 8
    defaults = StereoParams(**SGM_RECOMMENDED[0])  # census 7x7, P2 = 79: 1615, 1996, 1687
    assert (defaults.cost_bits, defaults.path_cost_bits, defaults.left_cost_bits,
            defaults.aggregated_cost_bits, defaults.left_loop_bits) == (6, 7, 11, 11, 12)


@pytest.mark.parametrize("cmax", [1, 24, 48, 6120, 91800])
@pytest.mark.parametrize("adapt", [None, 1])
def test_widths_hold_at_extreme_costs(cmax, adapt):
    """Golden equals the unbounded reference at the largest P2, costs only 0 and Cmax."""
    p2 = max_path_penalty(cmax)
    p1 = p2 // 3
    rng = np.random.default_rng(cmax)
    costs = random_volume(rng, 5, 9, 6, cmax, extreme=True)
    image = rng.choice([0, 255], (5, 9)).astype(np.uint8)
    parts = []
    for path in SGM_PATHS:
        expected = as_array(ref_path(costs.tolist(), path, p1, p2, image, adapt))
        got = golden_path(costs, path, p1, p2, image, adapt, max_cost=cmax)
        assert np.array_equal(got, expected), path
        bound = REF_K * cmax + p2 if path == "left" else cmax + p2
        bits = sgm_left_cost_bits(cmax, p2) if path == "left" else sgm_path_cost_bits(cmax, p2)
        assert 0 <= expected.min() and expected.max() <= bound < 2 ** bits
        parts.append(got)
    assert sum(parts).max() < 2 ** sgm_summed_cost_bits(cmax, p2)


@pytest.mark.parametrize("cmax, p1, p2", [(24, 12, 103), (24, 1, 24), (80, 0, 431), (3, 3, 3)])
def test_path_width_bound_is_reached(cmax, p1, p2):
    """A column of costs [0, Cmax, ..., Cmax] drives the far disparity of the top path to
    exactly Cmax + P2, so bitlen(Cmax + P2) bits are needed, not just sufficient."""
    # Each step down can raise the far disparities by at most Cmax, and P1 = 0 lets a
    # disparity rise only as far as its distance from d = 0 allows: enough of both.
    disparities = p2 // cmax + 3
    column = [[[0] + [cmax] * (disparities - 1)]] * (p2 // cmax + 5)
    costs = np.array(column, dtype=np.int64)
    expected = as_array(ref_path(costs.tolist(), "top", p1, p2))
    got = golden_path(costs, "top", p1, p2, max_cost=cmax)
    assert np.array_equal(got, expected)
    assert got.max() == cmax + p2


# Ties ------------------------------------------------------------------------------------------


def test_ties_go_to_the_lowest_disparity():
    summed = np.full((1, 6, 4), 9, dtype=np.uint16)
    summed[0, 2, [1, 3]] = 2  # left tie between d = 1 and 3
    summed[0, 4, [0, 2]] = 1  # x = 4: ties at d = 0 and 2 -> right pixels 4 and 2
    summed[0, 5, [2, 3]] = 1  # ties for right pixel 3 (via d = 2) and 2 (via d = 3)
    left, right = sgm.winners(summed)
    assert left[0].tolist() == [0, 0, 1, 0, 0, 2]
    # dR(xr) = argmin_d S(xr + d, d) over d <= W-1-xr.
    expected_right = reference.right_map(summed[0:1].astype(int).tolist())[0]
    assert right[0].tolist() == expected_right
    assert right[0, 2] == 2 and right[0, 4] == 0


def test_right_map_excludes_disparities_beyond_the_frame():
    summed = np.full((1, 5, 4), 7, dtype=np.uint16)
    summed[0, :, 3] = 0  # d = 3 is cheapest wherever it exists (xr <= 1)
    _, right = sgm.winners(summed)
    assert right[0].tolist() == [3, 3, 0, 0, 0]


# Broken variants --------------------------------------------------------------------------------

BROKEN_LEFT, BROKEN_RIGHT = make_pair("ramp", 7, 16, 9)
BROKEN = dict(name="census", block=3, D=6, p1=2, p2=9, adapt=3, threshold=1)


def broken_case_differs():
    c = BROKEN
    params = StereoParams(transform=c["name"], block=c["block"], disparities=c["D"],
                          lr_threshold=c["threshold"])
    expected = ref_map(BROKEN_LEFT, BROKEN_RIGHT, c["name"], c["block"], c["D"], c["p1"],
                       c["p2"], SGM_PATHS, c["adapt"], c["threshold"])
    costs = as_array(ref_costs(BROKEN_LEFT, BROKEN_RIGHT, c["name"], c["block"], c["D"]))
    summed_expected = as_array(ref_summed(costs.tolist(), SGM_PATHS, c["p1"], c["p2"],
                                          BROKEN_LEFT, c["adapt"]))
    volume = sgm.cost_volume(BROKEN_LEFT, BROKEN_RIGHT, params)
    summed = sgm.aggregate(volume, c["p1"], c["p2"], guide=BROKEN_LEFT, adapt=c["adapt"],
                           max_cost=params.max_cost).astype(np.int64)
    result = sgm.disparity_map(BROKEN_LEFT, BROKEN_RIGHT, params, c["p1"], c["p2"],
                               adapt=c["adapt"])
    return (not np.array_equal(summed, summed_expected)
            or not np.array_equal(result.disparity, expected))


def test_broken_baseline_matches():
    assert not broken_case_differs()


def test_broken_wrong_penalty_is_caught():
    costs = random_volume(np.random.default_rng(1), 5, 8, 5, 24)
    expected = as_array(ref_path(costs.tolist(), "top", 3, 30))
    assert not np.array_equal(golden_path(costs, "top", 4, 30, max_cost=24), expected)
    assert not np.array_equal(golden_path(costs, "top", 3, 29, max_cost=24), expected)


def test_broken_path_direction_is_caught(monkeypatch):
    # Top-right computed as top-left (the mirrored diagonal).
    monkeypatch.setattr(sgm, "SGM_PATH_STEPS", {**SGM_PATH_STEPS, "top-right": (-1, -1)})
    assert broken_case_differs()


def test_broken_p1_neighbour_is_caught(monkeypatch):
    # Only the d - 1 neighbour gets P1; d + 1 is forgotten.
    def one_sided(costs, previous, p1, p2, out, scratch):
        minimum = previous.min(axis=1, keepdims=True)
        np.copyto(scratch, previous)
        np.minimum(scratch[:, 1:], previous[:, :-1] + p1, out=scratch[:, 1:])
        np.minimum(scratch, minimum + p2, out=scratch)
        scratch -= minimum
        np.add(costs, scratch, out=out)
    monkeypatch.setattr(sgm, "_step", one_sided)
    assert broken_case_differs()


def test_broken_normalisation_is_caught(monkeypatch):
    # Subtracting the current pixel's minimum instead of the predecessor's.
    original = sgm._step

    def renormalised(costs, previous, p1, p2, out, scratch):
        original(costs, previous, p1, p2, out, scratch)
        out -= out.min(axis=1, keepdims=True)
    monkeypatch.setattr(sgm, "_step", renormalised)
    assert broken_case_differs()


def test_broken_invalid_disparity_rule_is_caught(monkeypatch):
    # Cost 0 (the box pipeline's rule) instead of Cmax where x - d < 0.
    original = sgm._costs_disparity_last

    def zero_outside(left_t, right_t, params, dtype):
        volume = original(left_t, right_t, params, dtype)
        for d in range(params.disparities):
            volume[:, :d, d] = 0
        return volume
    monkeypatch.setattr(sgm, "_costs_disparity_last", zero_outside)
    assert broken_case_differs()


def test_broken_adaptive_shift_is_caught(monkeypatch):
    # One halving too many: s = bitlen(g) - t + 1.
    original = sgm.path_p2

    def off_by_one(guide, path, p1, p2, adapt=None):
        return original(guide, path, p1, p2, None if adapt is None else adapt - 1)
    monkeypatch.setattr(sgm, "path_p2", off_by_one)
    assert broken_case_differs()


def test_broken_border_wraps_around(monkeypatch):
    # The left path continuing from the previous row's last pixel instead of starting fresh.
    original = sgm._left_band

    def wrapping(costs, p1, p2_map, out):
        rows, width, d = costs.shape
        flat = original(costs.reshape(1, rows * width, d), p1, p2_map.reshape(1, -1),
                        out.reshape(1, rows * width, d))
        return flat.reshape(costs.shape)
    monkeypatch.setattr(sgm, "_left_band", wrapping)
    assert broken_case_differs()


def test_broken_tie_rule_is_caught():
    summed = np.zeros((1, 3, 3), dtype=np.uint16)
    left, _ = sgm.winners(summed)
    highest = summed.shape[2] - 1 - np.argmin(summed[..., ::-1], axis=2)
    assert left.tolist() == [[0, 0, 0]] and not np.array_equal(left, highest)


# Through the pipeline: StereoParams(aggregation="sgm") -----------------------------------------

#: The golden SGM function as the pipeline must call it (kept before any monkeypatch).
DIRECT = sgm.disparity_map

#: SGM configurations as StereoParams fields: explicit penalties, adaptive P2 off (0), no
#: check, several rounds, the defaults (24/79/t=5, resolved by StereoParams), ext. census.
PIPELINE_CASES = [
    dict(transform="census", block=3, disparities=6, lr_threshold=1, p1=2, p2=9, p2_adapt=3),
    dict(transform="rank", block=5, disparities=5, lr_threshold=None, p1=1, p2=4, p2_adapt=0),
    dict(transform="census", block=5, disparities=8, rounds=4, lr_threshold=3),
    dict(transform="ext-census", block=3, disparities=4, lr_threshold=0, p1=300, p2=1500,
         p2_adapt=2),
]


def pipeline_matches(fields, left, right):
    """golden.pipeline.disparity_map of the SGM configuration ``fields`` equals the golden
    SGM called directly with its penalties (all three maps) and the plain reference."""
    params = StereoParams(aggregation="sgm", **fields)
    got = pipeline.disparity_map(left, right, params)
    adapt = params.p2_adapt or None
    direct = DIRECT(left, right, params, params.p1, params.p2, adapt=adapt)
    expected = ref_map(left, right, params.transform, params.block, params.disparities,
                       params.p1, params.p2, SGM_PATHS, adapt, params.lr_threshold)
    return (np.array_equal(got.disparity, direct.disparity)
            and np.array_equal(got.left, direct.left) and np.array_equal(got.right, direct.right)
            and got.disparity.dtype == direct.disparity.dtype
            and np.array_equal(got.disparity, expected))


@pytest.mark.parametrize("fields", PIPELINE_CASES, ids=lambda f: f"{f['transform']}{f['block']}")
def test_pipeline_computes_sgm_from_the_parameters(fields):
    left, right = make_pair("ramp", 7, 18, fields["block"])
    assert pipeline_matches(fields, left, right)


def test_pipeline_sgm_differs_from_the_box():
    # Counterpart: the same transform with the box gives another map, so the equality above
    # is not the box pipeline agreeing with itself.
    left, right = make_pair("ramp", 7, 18, 3)
    fields = dict(PIPELINE_CASES[0])
    box = StereoParams(transform="census", block=3, disparities=6, lr_threshold=1)
    sgm_map = pipeline.disparity_map(left, right, StereoParams(aggregation="sgm", **fields))
    assert not np.array_equal(sgm_map.disparity, pipeline.disparity_map(left, right, box).disparity)


@pytest.mark.parametrize("broken, case", [("adapt dropped", 0), ("golden defaults", 1),
                                          ("no check", 0)])
def test_broken_pipeline_dispatch_is_caught(monkeypatch, broken, case):
    """A pipeline that loses one of the configuration's SGM values fails the comparison."""
    def dispatch(left, right, params, p1, p2, paths=SGM_PATHS, adapt=None, threads=None):
        if broken == "adapt dropped":
            adapt = None
        elif broken == "golden defaults":
            p1, p2 = SGM_DEFAULT_P1, SGM_DEFAULT_P2
        else:
            params = params.replace(lr_threshold=None)
        return DIRECT(left, right, params, p1, p2, paths, adapt, threads)
    monkeypatch.setattr(sgm, "disparity_map", dispatch)
    fields = PIPELINE_CASES[case]
    left, right = make_pair("ramp", 7, 18, fields["block"])
    assert not pipeline_matches(fields, left, right)


# Parameters ----------------------------------------------------------------------------------


@pytest.mark.parametrize("p1, p2, adapt, paths, message", [
    (-1, 5, None, SGM_PATHS, "P1 must be an integer >= 0"),
    (1.5, 5, None, SGM_PATHS, "P1 must be an integer >= 0"),
    (6, 5, None, SGM_PATHS, "P2 must be an integer >= P1 (6)"),
    (1, 104, None, SGM_PATHS, "P2 must be <= 103"),
    (1, 8, 0, SGM_PATHS, "adaptive P2 exponent must be an integer 1 .. 7"),
    (1, 8, 8, SGM_PATHS, "adaptive P2 exponent"),
    (1, 8, None, ("left", "left"), "SGM paths must be distinct"),
    (1, 8, None, ("bottom",), "SGM paths must be distinct"),
    (1, 8, None, (), "SGM paths must be distinct"),
])
def test_bad_parameters_are_rejected(p1, p2, adapt, paths, message):
    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)")):
        check_penalties(24, p1, p2, adapt)
        check_sgm_paths(paths)


def test_bad_volumes_are_rejected():
    costs = np.full((3, 4, 5), 24, dtype=np.uint16)
    with pytest.raises(ParameterError, match="matching costs must be <= Cmax = 23, not 24"):
        sgm.path_costs(costs, "left", 1, 5, max_cost=23)
    with pytest.raises(ParameterError, match="cost volume must be"):
        sgm.path_costs(costs[0], "left", 1, 5, max_cost=24)
    with pytest.raises(ParameterError, match="guide image must be 4x3"):
        sgm.path_costs(costs, "top", 1, 5, guide=np.zeros((4, 3), np.uint8), adapt=2)
    with pytest.raises(ParameterError, match="needs the left gray image"):
        sgm.path_costs(costs, "top", 1, 5, adapt=2)
    with pytest.raises(ParameterError, match="SGM path must be one of"):
        sgm.path_costs(costs, "bottom", 1, 5)
    # Counterpart: Cmax equal to the largest cost is fine.
    assert sgm.path_costs(costs, "left", 1, 5, max_cost=24).shape == costs.shape


def test_boundary_parameters_are_accepted():
    # Counterpart: the edges of every allowed range pass.
    for p1, p2, adapt in ((0, 0, None), (0, 103, 1), (103, 103, 7)):
        check_penalties(24, p1, p2, adapt)
    check_sgm_paths(("top",))


@pytest.mark.parametrize("path, step", [("right", (1, 0)), ("bottom", (0, 1)),
                                        ("bottom-left", (-1, 1)), ("far-left", (-2, 0)),
                                        ("two-up", (0, -2))])
def test_paths_a_raster_order_stream_cannot_compute_are_refused(path, step):
    """The golden model computes every path with dy = 0 as the left one: a path from the
    right (or from below, or not from a neighbour) must not get that far."""
    with pytest.raises(ParameterError) as error:
        sgm_path_steps({**SGM_PATH_STEPS, path: step})
    assert str(error.value) == (f"SGM path '{path}' cannot be computed in raster order: its "
                                f"predecessor (dx, dy) must be (-1, 0) or (-1 .. 1, -1), "
                                f"not {step}")
    # Counterpart: the four paths themselves pass, read-only.
    assert dict(sgm_path_steps(SGM_PATH_STEPS)) == dict(SGM_PATH_STEPS)
