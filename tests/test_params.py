"""Every parameter StereoParams rejects, with a one-line message naming the parameter."""

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
    {"disparities": 16, "width": 17, "height": 1}])
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
