"""Random configurations (Hypothesis): golden model against the hardware, bit for bit.

Each example is a command line of ``npstereo cosim`` on a crop of the seeded synthetic
scene: the parameters are drawn from what :class:`~npstereo.params.StereoParams` accepts
(its tuples of transforms, line buffers and LUT sizes, the SGM penalties' range from
``max_path_penalty``, the frame width from ``first_valid_column``; a draw it refuses is
rejected, not filtered by a table of ours), parsed by the real command-line parser and cut
by the command's own frame code, so that a failure prints the command that reproduces it
and Hypothesis shrinks it to a minimal configuration first.

``make test`` runs a fixed seed (derandomized) and a small budget in Amaranth's simulator
plus one configuration under Verilator; ``make soak`` a long one (``SOAK_EXAMPLES``), and
says how many configurations passed. ``test_broken_hardware_is_caught`` shows that the same
property fails on a core with a wrong tie rule.
"""

import os
import shlex

import pytest
from hypothesis import HealthCheck, Phase, given, reject, settings
from hypothesis import strategies as st

from npstereo.gen.cli import cmd_cosim
from npstereo.gen.cli.arguments import params_from_args
from npstereo.gen.cli.main import build_parser
from npstereo.hdl import subpixel as hdl_subpixel
from npstereo.hdl import trees
from npstereo.hdl.plan import check_buildable, sgm_min_width
from npstereo.params import (LINE_BUFFERS, LUT_INPUTS, MAX_SUBPIXEL_BITS, P2_ADAPT_OFF, SGM,
                             SGM_MAX_ADAPT, TRANSFORMS, ParameterError, StereoParams,
                             max_path_penalty)
from npstereo.sim.cosim import run_frame

#: Examples per run: a minute of Amaranth's simulator in ``make test``; ``make soak`` sets
#: SOAK_EXAMPLES. The Verilator subset builds a model per example (ccache helps little
#: across configurations): one in ``make test``.
EXAMPLES = int(os.environ.get("SOAK_EXAMPLES", "14"))
VERILATOR_EXAMPLES = int(os.environ.get("SOAK_VERILATOR_EXAMPLES", "1"))
#: ``make soak`` draws new configurations each run unless SOAK_SEED fixes them.
DERANDOMIZE = "SOAK_EXAMPLES" not in os.environ

#: Small enough for Amaranth's simulator (a few thousand clocks per second): the cost is
#: W x H x R clocks plus the flush, and elaboration grows with B^2 and D.
BLOCKS = (3, 5)
#: ``npstereo cosim --synthetic`` makes its scene for D >= 8 (golden/synthetic.py), and the
#: failure must be reproducible with it.
MIN_DISPARITIES, MAX_DISPARITIES = 8, 10
MAX_EXTRA_WIDTH = 6
MAX_HEIGHT = 5

_PASSED = {"amaranth": 0, "verilator": 0}


@st.composite
def cosim_argv(draw, simulator="amaranth"):
    """An ``npstereo cosim`` command line of a valid configuration."""
    transform = draw(st.sampled_from(TRANSFORMS))
    block = draw(st.sampled_from(BLOCKS))
    disparities = draw(st.integers(MIN_DISPARITIES, MAX_DISPARITIES))
    rounds = draw(st.sampled_from([r for r in range(1, disparities + 1)
                                   if disparities % r == 0]))
    argv = ["--transform", transform, "--block", str(block), "--disparities",
            str(disparities), "--rounds", str(rounds)]
    if draw(st.booleans()):
        cmax = StereoParams(transform=transform, block=block).max_cost
        p2 = draw(st.integers(0, max_path_penalty(cmax)))
        p1 = draw(st.integers(0, p2))
        adapt = draw(st.sampled_from((P2_ADAPT_OFF, *range(1, SGM_MAX_ADAPT + 1))))
        argv += ["--aggregation", SGM, "--p1", str(p1), "--p2", str(p2)]
        argv += ["--no-p2-adapt"] if adapt == P2_ADAPT_OFF else ["--p2-adapt", str(adapt)]
    else:
        argv += ["--aggregation", str(draw(st.sampled_from((1, 3, 5))))]
    threshold = draw(st.none() | st.integers(0, 3))
    argv += ["--no-lr-check"] if threshold is None else ["--lr-threshold", str(threshold)]
    argv += ["--line-buffer", draw(st.sampled_from(LINE_BUFFERS)),
             "--lut-inputs", str(draw(st.sampled_from(LUT_INPUTS)))]
    # The output options: the 3x3 median, and whole levels half the time, F = 1 .. 5
    # fractional bits otherwise.
    if draw(st.booleans()):
        argv += ["--median"]
    if draw(st.booleans()):
        argv += ["--subpixel-bits", str(draw(st.integers(1, MAX_SUBPIXEL_BITS)))]
    try:
        params = params_from_args(_parse(["cosim", "--simulator", simulator, "--synthetic",
                                          "--out", "x", *argv]))
    except ParameterError:
        reject()
    narrowest = params.first_valid_column + 1
    if params.is_sgm:
        narrowest = max(narrowest, sgm_min_width(params.with_size(narrowest, 1)))
    width = draw(st.integers(narrowest, narrowest + MAX_EXTRA_WIDTH - 1))
    height = draw(st.integers(1, MAX_HEIGHT))
    seed = draw(st.integers(0, 2 ** 16))
    return ["cosim", "--simulator", simulator, "--synthetic", "--seed", str(seed),
            "--crop", f"{width}x{height}", *argv, "--out", "build/random-config"]


def _parse(argv):
    return build_parser(argv[0]).parse_args(argv)


def _check(argv):
    """Run the configuration of ``argv`` as ``npstereo cosim`` would, in-process; fail
    with the command when the hardware differs from the golden model."""
    args = _parse(argv)
    _, left, right = cmd_cosim._frame(args)
    params = params_from_args(args).with_size(left.shape[1], left.shape[0])
    check_buildable(params)
    result = run_frame(args.simulator, params, left, right)
    command = "npstereo " + shlex.join(argv)
    assert result.ok, f"{params.describe()}: {result.message()}\nreproduce: {command}"
    _PASSED[args.simulator] += 1


@settings(max_examples=EXAMPLES, derandomize=DERANDOMIZE, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(argv=cosim_argv())
def test_random_configurations_amaranth(argv):
    _check(argv)


@settings(max_examples=VERILATOR_EXAMPLES, derandomize=DERANDOMIZE, deadline=None,
          database=None, suppress_health_check=[HealthCheck.too_slow])
@given(argv=cosim_argv("verilator"))
def test_random_configurations_verilator(argv):
    _check(argv)


def test_broken_hardware_is_caught(monkeypatch):
    """Ties to the highest disparity in the partition WTA (``<=``): the same property must
    fail (no shrinking: the failure is what is tested, not its minimal form)."""
    monkeypatch.setattr(trees, "better", lambda candidate, best: candidate <= best)

    @settings(max_examples=10, derandomize=True, deadline=None, database=None,
              phases=[Phase.generate], suppress_health_check=list(HealthCheck))
    @given(argv=cosim_argv())
    def broken(argv):
        _check(argv)

    with pytest.raises(AssertionError, match="reproduce: npstereo cosim"):
        broken()


def test_broken_fraction_is_caught(monkeypatch):
    """The fit's offset rounded down instead of half up (the numerator without its a + b):
    the same property fails on the draws with F > 0."""
    monkeypatch.setattr(hdl_subpixel, "numerator",
                        lambda a, denominator, bits: a << (bits + 1))

    @settings(max_examples=10, derandomize=True, deadline=None, database=None,
              phases=[Phase.generate], suppress_health_check=list(HealthCheck))
    @given(argv=cosim_argv())
    def broken(argv):
        if "--subpixel-bits" in argv:
            _check(argv)

    with pytest.raises(AssertionError, match="reproduce: npstereo cosim .*--subpixel-bits"):
        broken()


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    print(f"\nrandom configurations passed: {_PASSED['amaranth']} in Amaranth's simulator, "
          f"{_PASSED['verilator']} under Verilator")


def test_strategy_draws_only_valid_configurations():
    """Every drawn command line parses and builds valid parameters (the strategy's own
    check, with no simulation)."""
    drawn = []

    @settings(max_examples=40, derandomize=True, database=None,
              suppress_health_check=list(HealthCheck))
    @given(argv=cosim_argv())
    def valid(argv):
        args = _parse(argv)
        _, left, _ = cmd_cosim._frame(args)
        params = params_from_args(args).with_size(left.shape[1], left.shape[0])
        check_buildable(params)
        drawn.append(params)

    valid()
    # The output options are drawn too, each of them on and off.
    assert {p.median for p in drawn} == {False, True}
    assert {p.subpixel_bits > 0 for p in drawn} == {False, True}
