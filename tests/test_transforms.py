"""Every transform through every per-transform table, and the tables' check at import.

A transform is described once (``params.TRANSFORM_SPECS``); its functions live in tables
keyed by its name: the golden transform and cost, the hardware's transform and cost
(``params.check_transform_table`` checks each against ``TRANSFORMS`` at import), and the
independent reference's. The plans derive their tables from the description.
``run_everywhere`` takes one small configuration of a transform through all of them; the
broken variants remove one entry of each table and show that the run fails, and that the
check at import names the table.
"""

import dataclasses

import numpy as np
import pytest
from amaranth.hdl import Fragment

from npstereo.golden import matching_cost as golden_cost
from npstereo.golden import transform as golden_transform
from npstereo.golden.pipeline import disparity_map
from npstereo.hdl import matching_cost as hdl_cost
from npstereo.hdl import plan_memories, plan_structure, plan_timing
from npstereo.hdl import transform as hdl_transform
from npstereo.hdl.matching_cost import MatchingCost
from npstereo.hdl.transform import Transform
from npstereo.params import TRANSFORM_SPECS, TRANSFORMS, StereoParams, check_transform_table

import reference
from scenes import stereo_pair

#: Every table of per-transform functions: (module, attribute) of a dict keyed by name.
TABLES = {
    "golden transforms": (golden_transform, "_TRANSFORMS"),
    "golden costs": (golden_cost, "_COSTS"),
    "hardware transforms": (hdl_transform, "_TRANSFORMS"),
    "hardware costs": (hdl_cost, "_COSTS"),
    "reference transforms": (reference, "TRANSFORMS"),
    "reference costs": (reference, "COSTS"),
}


def run_everywhere(name):
    """Transform ``name`` through every table: the golden transform, costs and map of a
    small pair equal to the reference's; the hardware's transform and cost elaborated, with
    the plans' latencies; the plans' copies, masks, memories and timing."""
    params = StereoParams(transform=name, block=3, disparities=4, rounds=2, width=12,
                          height=5)
    left, right = stereo_pair("levels", params.height, params.width, seed=1)
    left_t = golden_transform.transform(left, params)
    right_t = golden_transform.transform(right, params)
    volume = reference.cost_volume(left, right, name, params.block, params.disparities)
    for d in range(params.disparities):
        expected = [[volume[y][x][d] for x in range(params.width)]
                    for y in range(params.height)]
        assert np.array_equal(golden_cost.matching_costs(left_t, right_t, d, params),
                              expected), d
    expected = reference.disparity_map(left, right, name, params.block, params.disparities)
    assert np.array_equal(disparity_map(left, right, params).disparity, expected)
    pixels = params.replace(line_buffer="pixels")
    for unit, plan in ((Transform(pixels, copies=plan_structure.centre_copies(pixels),
                                  mask_after=plan_structure.masks_after_compare(pixels)),
                        plan_structure.transform_plan(
                            pixels, mask_after=plan_structure.masks_after_compare(pixels))),
                       (MatchingCost(params), plan_structure.cost_plan(params))):
        Fragment.get(unit, None)
        assert unit.latency == sum(plan)
    assert params.stored_rows == TRANSFORM_SPECS[name].auto_stored_rows
    assert plan_memories.memory_bits(params) > 0
    assert plan_timing.core_timing(params).output > 0


def test_the_tables_cover_exactly_the_described_transforms():
    assert TRANSFORMS == tuple(TRANSFORM_SPECS) == ("rank", "census", "ext-rank",
                                                    "ext-census")
    for what, (module, attribute) in TABLES.items():
        assert tuple(getattr(module, attribute)) == TRANSFORMS, what


@pytest.mark.parametrize("name", TRANSFORMS)
def test_every_transform_runs_through_every_table(name):
    run_everywhere(name)


# A component whose elaboration fails half way is never used: Amaranth says so.
@pytest.mark.filterwarnings("ignore:.*created but never used")
@pytest.mark.parametrize("table", TABLES)
def test_a_transform_missing_from_a_table_fails(monkeypatch, table):
    """Broken variant: ext. census removed from one table; the run fails there, and the
    check the table passes at import names it."""
    module, attribute = TABLES[table]
    entries = getattr(module, attribute)
    monkeypatch.delitem(entries, "ext-census")
    with pytest.raises(KeyError, match="ext-census"):
        run_everywhere("ext-census")
    with pytest.raises(LookupError) as error:
        check_transform_table(entries, table)
    assert str(error.value) == (f"{table} must have one entry per transform (rank, census, "
                                f"ext-rank, ext-census): missing ext-census, unknown none")
    run_everywhere("census")  # Counterpart: the other transforms still run.


def test_an_unknown_transform_in_a_table_fails():
    with pytest.raises(LookupError) as error:
        check_transform_table({**golden_transform._TRANSFORMS, "mini-census": None},
                              "golden transforms")
    assert str(error.value).endswith("missing none, unknown mini-census")
    # Counterpart: the table as it is passes, unchanged.
    table = golden_transform._TRANSFORMS
    assert check_transform_table(table, "golden transforms") is table


def test_a_description_with_an_unknown_choice_fails():
    spec = TRANSFORM_SPECS["census"]
    with pytest.raises(ValueError, match="census: cost_reduction must be one of"):
        dataclasses.replace(spec, cost_reduction="xor")
    with pytest.raises(ValueError, match="census: auto_stored_rows must be one of"):
        dataclasses.replace(spec, auto_stored_rows="auto")


def test_the_sums_of_differences_are_those_of_the_extended_transforms():
    assert [name for name in TRANSFORMS if TRANSFORM_SPECS[name].sums_differences] == \
        ["ext-rank", "ext-census"]
