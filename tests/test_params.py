"""Every parameter StereoParams rejects, with a one-line message naming the parameter."""

import dataclasses

import numpy as np
import pytest

from npstereo.params import ParameterError, StereoParams, UserError

BAD = [
    ({"block": 8}, "block"),              # even
    ({"block": 1}, "block"),              # too small
    ({"block": 3.0}, "block"),            # not an integer
    ({"disparities": 1}, "disparities"),
    ({"disparities": 0}, "disparities"),
    ({"rounds": 0}, "rounds"),
    ({"disparities": 10, "rounds": 3}, "rounds must divide"),
    ({"transform": "sad"}, "transform"),
    ({"aggregation": 2}, "aggregation"),
    ({"aggregation": 0}, "aggregation"),
    ({"lr_threshold": -1}, "lr threshold"),
    ({"disparities": 16, "width": 16, "height": 8}, "width"),   # width <= first valid column
    ({"disparities": 16, "aggregation": 5, "width": 17, "height": 8}, "width"),
    ({"height": 0, "width": 200}, "height"),
    ({"lut_inputs": 5}, "lut inputs must be one of 4, 6, not 5"),
    ({"lut_inputs": "6"}, "lut inputs"),
    ({"lut_inputs": True}, "lut inputs"),
]


def assert_rejected(changes, word):
    """StereoParams(**changes) raises a one-line ParameterError mentioning ``word``."""
    with pytest.raises(ParameterError) as info:
        StereoParams(**changes)
    message = str(info.value)
    assert word in message and "\n" not in message
    assert isinstance(info.value, UserError)


@pytest.mark.parametrize("changes, word", BAD, ids=[str(c) for c, _ in BAD])
def test_bad_parameters_are_rejected(changes, word):
    assert_rejected(changes, word)


def test_the_rejection_check_fails_on_a_valid_configuration():
    # The helper above must not pass vacuously: a valid configuration makes it fail.
    with pytest.raises(pytest.fail.Exception, match="DID NOT RAISE"):
        assert_rejected({"block": 9}, "block")


@pytest.mark.parametrize("changes", [
    {"block": 3, "disparities": 2}, {"disparities": 10, "rounds": 5},
    {"aggregation": 1, "lr_threshold": None}, {"lr_threshold": 0},
    {"disparities": 16, "width": 17, "height": 1}, {"lut_inputs": 6}])
def test_boundary_values_are_accepted(changes):
    params = StereoParams(**changes)
    assert {name: getattr(params, name) for name in changes} == changes


def test_replace_validates():
    params = StereoParams(disparities=10, rounds=5)
    assert params.replace(rounds=2).rounds == 2 and params.rounds == 5
    with pytest.raises(ParameterError, match="rounds must divide"):
        params.replace(rounds=3)
    with pytest.raises(ParameterError, match="image width"):
        params.with_size(10, 4)


def test_first_valid_column_and_widths():
    params = StereoParams(transform="census", block=9, disparities=100)
    assert params.first_valid_column == 100
    assert params.transform_bits == 80
    assert StereoParams(disparities=16, aggregation=5).first_valid_column == 17


# Semi-global aggregation ------------------------------------------------------------------

SGM_BAD = [
    ({"p1": -1}, "P1 must be an integer >= 0, not -1"),
    ({"p1": 1.5}, "P1 must be an integer >= 0, not 1.5"),
    ({"p1": 30, "p2": 20}, "P2 must be an integer >= P1 (30), not 20"),
    ({"p2": 10}, "P2 must be an integer >= P1 (24), not 10 (SGM defaults P1 = 24, P2 = 79)"),
    ({"p1": 5, "p2": "9"}, "P2 must be an integer >= P1 (5), not '9'"),
    ({"block": 5, "p1": 16, "p2": 104},
     "P2 must be <= 103 for a matching cost of at most 24 (path cost at most 7 bits), not 104"),
    # Census 3x3 (Cmax = 8) cannot take the default P2: the message says it was the default.
    ({"block": 3}, "P2 must be <= 55 for a matching cost of at most 8 (path cost at most "
                   "6 bits), not 79 (SGM defaults P1 = 24, P2 = 79)"),
    ({"p2_adapt": 8}, "adaptive P2 exponent must be an integer 1 .. 7 (or off), not 8"),
    ({"p2_adapt": -1}, "adaptive P2 exponent must be an integer 1 .. 7 (or off), not -1"),
    ({"p2_adapt": False}, "adaptive P2 exponent must be an integer 1 .. 7 (or off), not False"),
    ({"aggregation": "SGM"}, "aggregation must be an odd window size >= 1 or 'sgm', not 'SGM'"),
    ({"aggregation": 3, "p1": 3}, "p1 is an SGM parameter: it needs aggregation 'sgm', not a "
                                  "3x3 box"),
    ({"aggregation": 5, "p2": 3}, "p2 is an SGM parameter: it needs aggregation 'sgm', not a "
                                  "5x5 box"),
    ({"aggregation": 1, "p2_adapt": 0}, "p2_adapt is an SGM parameter: it needs aggregation "
                                        "'sgm', not a 1x1 box"),
    ({"disparities": 16, "width": 16, "height": 8},
     "image width must be an integer > 16 for 16 disparities (first valid column 16), not 16"),
]


def assert_rejected_exactly(changes, message):
    """StereoParams(census 7x7 SGM, **changes) raises ParameterError with ``message``."""
    fields = {"transform": "census", "block": 7, "aggregation": "sgm", **changes}
    with pytest.raises(ParameterError) as info:
        StereoParams(**fields)
    assert str(info.value) == message


@pytest.mark.parametrize("changes, message", SGM_BAD, ids=[str(c) for c, _ in SGM_BAD])
def test_bad_sgm_parameters_are_rejected(changes, message):
    assert_rejected_exactly(changes, message)


def test_the_exact_rejection_check_can_fail():
    # Not vacuous: a valid configuration and a different message both fail it.
    with pytest.raises(pytest.fail.Exception, match="DID NOT RAISE"):
        assert_rejected_exactly({"p1": 1}, "P1 must be an integer >= 0, not 1")
    with pytest.raises(AssertionError):
        assert_rejected_exactly({"p1": -2}, "P1 must be an integer >= 0, not -1")


def test_sgm_defaults_are_resolved_in_the_object():
    params = StereoParams(transform="census", block=7, aggregation="sgm")
    assert (params.p1, params.p2, params.p2_adapt) == (24, 79, 5)
    assert params.describe() == "census 7x7 D=100 R=1 SGM P1=24 P2=79 t=5 LR=3"
    off = StereoParams(aggregation="sgm", p2_adapt=0, p1=np.int64(3), p2=np.int32(40))
    assert (off.p1, off.p2, off.p2_adapt) == (3, 40, 0) and type(off.p1) is int
    assert off.describe().endswith("SGM P1=3 P2=40 t=off LR=3")
    # Counterpart: a box keeps None and says A=.
    box = StereoParams()
    assert (box.p1, box.p2, box.p2_adapt) == (None, None, None)
    assert " A=3 " in box.describe() and not box.is_sgm and box.path_cost_bits is None


@pytest.mark.parametrize("params", [
    StereoParams(aggregation="sgm"), StereoParams(aggregation="sgm", p2_adapt=0),
    StereoParams(aggregation="sgm", width=120, height=9, rounds=4), StereoParams()],
    ids=["sgm", "sgm-off", "sgm-sized", "box"])
def test_fields_round_trip(params):
    # sim/cocotb_tests.py and the report cache rebuild parameters from asdict().
    again = StereoParams(**dataclasses.asdict(params))
    assert again == params and repr(again) == repr(params)
    assert params.with_size(150, 7).replace(width=None, height=None) == params.replace(
        width=None, height=None)


@pytest.mark.parametrize("changes", [
    {"p1": 0, "p2": 0}, {"p1": 207, "p2": 207}, {"p1": 0, "p2": 207, "p2_adapt": 1},
    {"p2_adapt": 7}, {"p2_adapt": 0}, {"transform": "ext-census", "block": 3, "p1": 0,
                                        "p2": 6151}])
def test_sgm_boundary_values_are_accepted(changes):
    params = StereoParams(**{"transform": "census", "block": 7, "aggregation": "sgm",
                             **changes})
    assert {name: getattr(params, name) for name in changes} == changes


@pytest.mark.parametrize("fields, summed, path", [
    # S: the left path's 32 Cmax + P2 plus 3 (Cmax + P2) from the row above.
    # Default census 7x7: Cmax 48, 1615 + 3 x 127 = 1996 < 2048, 48 + 79 = 127 < 128.
    ({"block": 7}, 11, 7),
    # Census 5x5, P2 96: 864 + 3 x 120 = 1224, 120.
    ({"block": 5, "p1": 16, "p2": 96, "p2_adapt": 4}, 11, 7),
    # One step further: census 7x7 with P2 = 80 needs an 8-bit path cost.
    ({"block": 7, "p2": 80}, 11, 8),
    # Census 9x9 at P2max = 431: 80 + 431 = 511 (9 bits), 2991 + 1533 = 4524 (13 bits).
    ({"block": 9, "p2": 431}, 13, 9),
    # Ext. census 3x3, Cmax 2040: 66,180 + 3 x 2940 = 75,000 (17 bits).
    ({"transform": "ext-census", "block": 3, "p1": 100, "p2": 900}, 17, 12),
])
def test_sgm_widths_and_geometry(fields, summed, path):
    params = StereoParams(**{"transform": "census", "aggregation": "sgm", "disparities": 16,
                             **fields})
    assert params.is_sgm and params.agg_radius == 0
    assert (params.aggregated_cost_bits, params.path_cost_bits) == (summed, path)
    # The invalid border of SGM is x < D (docs/semantics.md): width D + 1 is the smallest.
    assert params.first_valid_column == 16
    assert params.with_size(17, 1).width == 17
    # The box of the same transform keeps its own widths (A = 3: bitlen(9 Cmax)).
    box = StereoParams(transform=params.transform, block=params.block)
    assert box.aggregated_cost_bits == (9 * params.max_cost).bit_length()
