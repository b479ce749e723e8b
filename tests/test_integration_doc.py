"""docs/integration.md runs as shown: its ``sh`` blocks, in order, in an empty folder.

Broken variant: a block whose command fails stops the run with its exit code (bash -e),
so a step of the page that stops working fails this test.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parent.parent / "docs" / "integration.md"


def sh_blocks(text):
    return re.findall(r"^```sh\n(.*?)^```$", text, re.S | re.M)


def run_blocks(blocks, folder):
    """Run the blocks as one bash -e script in ``folder`` with this environment's
    ``bin`` first on PATH (as the page asks); (exit code, output)."""
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    result = subprocess.run(["bash", "-e", "-c", "\n".join(blocks)], cwd=folder, env=env,
                            capture_output=True, text=True, timeout=600, check=False)
    return result.returncode, result.stdout + result.stderr


def test_every_command_of_the_page_works(tmp_path):
    blocks = sh_blocks(DOC.read_text())
    assert len(blocks) >= 4
    code, output = run_blocks(blocks, tmp_path)
    assert code == 0, output
    assert "npstereo_core_tb: PASS: 384 pixels bit-exact with the golden model" in output
    assert "%Warning" not in output
    assert "s_axis axis" in output and "m_axis_tdata out 8" in output
    assert (tmp_path / "build" / "ip" / "census5" / "component.xml").exists()


@pytest.mark.parametrize("broken", ["npstereo ip --block 4 --width 8 --height 4 --out x",
                                    "fusesoc run --target lint no:such:core:0"])
def test_a_failing_step_fails_the_run(tmp_path, broken):
    code, output = run_blocks([broken, "echo after"], tmp_path)
    assert code != 0 and "after" not in output
