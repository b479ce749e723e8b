"""Shared fixtures: small seeded synthetic stereo pairs (no external data in tests), the
libraries a command loads; the tests marked ``dask`` kept together."""

import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from npstereo.golden.synthetic import synthetic_pair


@pytest.fixture(scope="session")
def small_pair():
    """A 64 x 40 RGB pair made for D = 16, seed 1, with exact integer ground truth."""
    return synthetic_pair(width=64, height=40, disparities=16, seed=1)


@pytest.fixture(scope="session")
def default_pair():
    """The embedded default scene of ``make demo`` (160 x 120, D = 32, seed 0)."""
    return synthetic_pair()


@pytest.fixture
def pair_files(tmp_path, small_pair):
    """The small synthetic pair as RGB PNGs and a Middlebury-2003 folder."""
    left, right = tmp_path / "left.png", tmp_path / "right.png"
    Image.fromarray(small_pair.left).save(left)
    Image.fromarray(small_pair.right).save(right)
    scene = tmp_path / "scene"
    scene.mkdir()
    Image.fromarray(small_pair.left).save(scene / "im2.png")
    Image.fromarray(small_pair.right).save(scene / "im6.png")
    Image.fromarray((4 * small_pair.ground_truth).astype(np.uint8)).save(scene / "disp2.pgm")
    return left, right, scene


@pytest.fixture
def libraries_loaded():
    """``loaded(argv, names)``: run ``npstereo argv`` in a fresh interpreter; returns its
    exit code, its standard output and which of the top-level modules ``names`` it
    imported (sorted)."""
    def loaded(argv, names):
        script = ("import sys\nfrom npstereo.gen.cli.main import main\n"
                  f"try:\n    code = main({list(argv)!r})\n"
                  "except SystemExit as exit:\n    code = exit.code\n"
                  f"print(sorted({{m.split('.')[0] for m in sys.modules}} & {set(names)!r}))\n"
                  "sys.exit(code)\n")
        result = subprocess.run([sys.executable, "-c", script], capture_output=True,
                                text=True, timeout=120, check=False)
        *output, modules = result.stdout.splitlines() or [""]
        return result.returncode, "\n".join(output), modules
    return loaded


def pytest_collection_modifyitems(items):
    """Tests marked ``dask`` start a cluster of 2 worker processes each: under ``make
    test`` (``pytest -n 2 --dist loadgroup``) they share one xdist worker, so two clusters
    never compete for the 2 cores and a module's cluster fixture runs once."""
    for item in items:
        if item.get_closest_marker("dask") is not None:
            item.add_marker(pytest.mark.xdist_group("dask"))
