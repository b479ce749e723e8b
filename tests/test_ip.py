"""``npstereo ip``: the packages read by the real tools of each flow.

- FuseSoC (from PyPI) runs the package's ``lint`` target (Verilator, -Wall less the
  documented waivers: exit 0, no warning) and its ``sim`` target (Icarus, one frame
  compared with the golden model bit for bit); and it runs the generator core for a user's
  core that asks for a configuration by parameters.
- ``component.xml`` is valid against the IEEE 1685-2014 schema and ipyxact finds both
  AXI4-Stream interfaces with the Verilog's widths, for two configurations whose output
  widths differ (8 and 16 bits).
- ``_hw.tcl`` runs in a Tcl interpreter with the Platform Designer commands as recorders
  and declares the same interfaces (tests/ip_readers.py).

Each check has a broken variant that it must catch. Bad input is one line, exit 2, and
nothing written.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from npstereo.gen.cli.main import main
from npstereo.gen.ip.fusesoc import LINT_OPTIONS
from npstereo.gen.ip.package import COMPONENT_FILE, CORE_FILE, HW_TCL_FILE, VERILOG_FILE
from npstereo.sim.tools import tool_env

from ip_readers import (component_problems, hw_tcl_problems, read_component,
                        verilog_ports)

FUSESOC = Path(sys.executable).parent / "fusesoc"
VLNV = "npstereo:stereo:npstereo_core:0.1.0"

#: Two configurations whose m_axis_tdata widths differ: D = 8 needs 3 + 1 bits (one
#: byte), D = 136 needs 8 + 1 (two bytes).
CONFIGURATIONS = {
    "census-d8": (["--transform", "census", "--block", "3", "--disparities", "8",
                   "--width", "16", "--height", "4"], 8),
    "rank-d136": (["--transform", "rank", "--block", "3", "--disparities", "136",
                   "--rounds", "17", "--aggregation", "1", "--no-lr-check",
                   "--width", "140", "--height", "3"], 16),
}


@pytest.fixture(scope="module")
def packages(tmp_path_factory):
    """{configuration: (package folder, m_axis width, Verilog ports)}."""
    made = {}
    for name, (argv, width) in CONFIGURATIONS.items():
        out = tmp_path_factory.mktemp(name)
        assert main(["ip", *argv, "--out", str(out)]) == 0
        made[name] = (out, width, verilog_ports(out / VERILOG_FILE))
    return made


def _fusesoc(cores, target, vlnv, cwd):
    """``fusesoc run`` with the project's Verilator on PATH; (exit code, output)."""
    cwd.mkdir(exist_ok=True)
    command = [str(FUSESOC)]
    for root in cores:
        command += ["--cores-root", str(root)]
    result = subprocess.run([*command, "run", "--target", target, vlnv], cwd=cwd,
                            env=tool_env(), capture_output=True, text=True, timeout=300,
                            check=False)
    return result.returncode, result.stdout + result.stderr


def _copy(package, folder):
    folder.mkdir()
    for path in package.iterdir():
        (folder / path.name).write_bytes(path.read_bytes())
    return folder


# --- FuseSoC ---------------------------------------------------------------------------

def test_fusesoc_lint_target_is_clean(packages, tmp_path):
    """fusesoc lint: exit 0 and not one Verilator warning beyond the waivers; broken
    variant: the same core without one waiver fails on that warning."""
    package = packages["census-d8"][0]
    code, output = _fusesoc([package], "lint", VLNV, tmp_path)
    assert code == 0, output
    assert "--lint-only" in (next((tmp_path / "build").rglob("*.vc"))).read_text()
    assert "%Warning" not in output and "%Error" not in output, output
    # FuseSoC's and Edalize's own warnings too (the legacy tool API would print one).
    assert not re.search(r"^WARNING", output, re.M), output
    broken = _copy(package, tmp_path / "broken")
    core = broken / CORE_FILE
    core.write_text(core.read_text().replace('"-Wno-WIDTHEXPAND", ', ""))
    code, output = _fusesoc([broken], "lint", VLNV, tmp_path / "run-broken")
    assert code != 0 and "%Warning-WIDTHEXPAND" in output


def test_fusesoc_sim_target_is_bit_exact(packages, tmp_path):
    """fusesoc sim: the testbench passes the frame bit for bit; broken variant: one
    expected beat changed fails with the pixel named and a non-zero exit."""
    package = packages["census-d8"][0]
    code, output = _fusesoc([package], "sim", VLNV, tmp_path)
    assert code == 0, output
    assert "npstereo_core_tb: PASS: 64 pixels bit-exact" in output
    broken = _copy(package, tmp_path / "broken")
    expected = broken / "expected.hex"
    lines = expected.read_text().splitlines()
    lines[21] = f"{int(lines[21], 16) ^ 1:0{len(lines[21])}x}"
    expected.write_text("\n".join(lines) + "\n")
    code, output = _fusesoc([broken], "sim", VLNV, tmp_path / "run-broken")
    assert code != 0
    assert "pixel x=5 y=1" in output and "FAIL: 1 of 64 pixels differ" in output


USER_CORE = """\
CAPI=2:
name: "me:demo:mydesign:1.0"
filesets:
  rtl:
    depend: ["npstereo:stereo:generator"]
generate:
  stereo:
    generator: npstereo
    parameters: {parameters}
targets:
  default:
    filesets: [rtl]
    generate: [stereo]
  lint:
    filesets: [rtl]
    generate: [stereo]
    flow: lint
    flow_options:
      tool: verilator
      verilator_options: {options}
    toplevel: npstereo_core
"""


def _user_core(folder, parameters):
    folder.mkdir()
    options = "[" + ", ".join(f'"{option}"' for option in LINT_OPTIONS) + "]"
    (folder / "mydesign.core").write_text(USER_CORE.format(parameters=parameters,
                                                           options=options))
    return folder


def test_fusesoc_generator_makes_the_asked_core(tmp_path):
    """A user's core asks the generator for census 3x3, D = 8, 24 x 6: FuseSoC runs it,
    lints the core it made, and the made core is that configuration under the name
    FuseSoC gave it. Broken variant: an unknown parameter fails the run with the
    generator's one-line error."""
    generator = tmp_path / "generator"
    assert main(["ip", "--fusesoc-generator", "--out", str(generator)]) == 0
    user = _user_core(tmp_path / "user", "{transform: census, block: 3, disparities: 8, "
                                         "width: 24, height: 6, lr_threshold: off}")
    run = tmp_path / "run"
    code, output = _fusesoc([generator, user], "lint", "me:demo:mydesign:1.0", run)
    assert code == 0, output
    assert "%Warning" not in output
    (core,) = run.rglob(CORE_FILE)
    assert 'name: "me:demo:mydesign-stereo:1.0"' in core.read_text()
    _, _, parameters = read_component(core.parent / COMPONENT_FILE)
    assert (parameters["width"], parameters["height"], parameters["lr_check"]) == \
        ("24", "6", '"off"')
    bad = _user_core(tmp_path / "bad", "{transform: census, blocks: 3}")
    code, output = _fusesoc([generator, bad], "lint", "me:demo:mydesign:1.0",
                            tmp_path / "run-bad")
    assert code != 0
    assert "npstereo: error: unknown generator parameter blocks: allowed are" in output


# --- IP-XACT ---------------------------------------------------------------------------

@pytest.mark.parametrize("configuration", list(CONFIGURATIONS))
def test_ipxact_declares_both_streams_with_their_widths(packages, configuration):
    package, width, verilog = packages[configuration]
    assert verilog["m_axis_tdata"] == ("out", width)
    assert component_problems(package / COMPONENT_FILE, verilog) == []
    interfaces, ports, parameters = read_component(package / COMPONENT_FILE)
    assert ports["s_axis_tdata"] == ("in", 16) and ports["m_axis_tdata"] == ("out", width)
    assert ports["framing_error"] == ("out", 1)
    argv = CONFIGURATIONS[configuration][0]
    assert parameters["transform"] == f'"{argv[argv.index("--transform") + 1]}"'
    assert parameters["disparities"] == argv[argv.index("--disparities") + 1]


def test_ipxact_check_catches_broken_components(packages, tmp_path):
    """A wrong width, a mirrored mode and a file the schema rejects are each caught."""
    package, width, verilog = packages["census-d8"]
    text = (package / COMPONENT_FILE).read_text()
    tdata = re.search(r"<ipxact:name>m_axis_tdata</ipxact:name>\s*<ipxact:wire>.*?"
                      r"<ipxact:left>(\d+)</ipxact:left>", text, re.S)
    assert tdata.group(1) == str(width - 1)
    wrong_width = text[:tdata.start(1)] + str(width) + text[tdata.end(1):]
    swapped = text.replace("<ipxact:master />", "<ipxact:mirroredMaster />", 1)
    # The schema requires a vendor.
    no_vendor = text.replace("<ipxact:vendor>npstereo</ipxact:vendor>", "")
    cases = {"width": wrong_width, "mode": swapped}
    for name, broken in cases.items():
        path = tmp_path / f"{name}.xml"
        path.write_text(broken)
        assert component_problems(path, verilog), name
    invalid = tmp_path / "invalid.xml"
    invalid.write_text(no_vendor)
    with pytest.raises(Exception, match="not valid according to XML schema"):
        read_component(invalid)


# --- Platform Designer -----------------------------------------------------------------

@pytest.mark.parametrize("configuration", list(CONFIGURATIONS))
def test_hw_tcl_declares_the_same_interfaces(packages, configuration):
    package, width, verilog = packages[configuration]
    assert hw_tcl_problems(package / HW_TCL_FILE, verilog) == []
    text = (package / HW_TCL_FILE).read_text()
    assert f"add_interface_port m_axis m_axis_tdata tdata Output {width}\n" in text


def test_hw_tcl_check_catches_broken_components(packages, tmp_path):
    """A wrong width, a stream turned round, a role Platform Designer does not have and a
    command it does not know are each caught."""
    package, width, verilog = packages["census-d8"]
    text = (package / HW_TCL_FILE).read_text()
    cases = {
        "width": text.replace(f"m_axis_tdata tdata Output {width}",
                              f"m_axis_tdata tdata Output {width + 8}"),
        "direction": text.replace("add_interface m_axis axi4stream start",
                                  "add_interface m_axis axi4stream end"),
        "role": text.replace("s_axis_tuser tuser", "s_axis_tuser sof"),
    }
    for name, broken in cases.items():
        assert broken != text, name
        path = tmp_path / f"{name}_hw.tcl"
        path.write_text(broken)
        assert hw_tcl_problems(path, verilog), name
    unknown = tmp_path / "unknown_hw.tcl"
    unknown.write_text(text.replace("add_interface_port", "add_interface_pin", 1))
    with pytest.raises(Exception, match="invalid command name"):
        hw_tcl_problems(unknown, verilog)


# --- bad input -------------------------------------------------------------------------

SMALL = ["--block", "3", "--disparities", "8", "--width", "16", "--height", "4"]


@pytest.mark.parametrize("argv, message", [
    (["--block", "4", "--disparities", "8", "--width", "16", "--height", "4"], "block"),
    (["--block", "3", "--disparities", "8", "--width", "0", "--height", "4"], "width"),
    (["--block", "3", "--disparities", "8", "--height", "4"], "--width"),
    (["--lut-inputs", "5", *SMALL], "--lut-inputs"),
    (["--vlnv", "npstereo:core", *SMALL], "--vlnv"),
    (["--fusesoc-generator", *SMALL], "--fusesoc-generator"),
])
def test_bad_arguments_are_one_line(tmp_path, capsys, argv, message):
    out = tmp_path / "package"
    assert main(["ip", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("npstereo: error: ") and message in err[0], err
    assert not out.exists()


def test_out_into_a_file_is_one_line(tmp_path, capsys):
    target = tmp_path / "a-file"
    target.write_text("x")
    assert main(["ip", *SMALL, "--out", str(target)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"npstereo: error: --out {target} exists and is not a folder"]
    assert sorted(os.listdir(tmp_path)) == ["a-file"] and target.read_text() == "x"
