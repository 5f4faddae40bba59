"""The tool's --config files and the parameters its --json records."""
import json
import pathlib
import re
import subprocess

import pytest

import normalflow as nf
from normalflow import _normalflow


def smooth(cli, *args):
    p = subprocess.run([cli, "smooth", *map(str, args)], capture_output=True, text=True)
    report = json.loads(p.stdout.strip().splitlines()[-1]) if "--json" in args and p.returncode == 0 else None
    return p.returncode, report, p.stderr


@pytest.fixture(scope="module")
def part(data):
    return data / "pairs_gnf" / "twelve_imp0.5.ply"


def test_a_config_file_is_its_flags_and_the_command_line_wins(cli, part, tmp_path):
    config = tmp_path / "smooth.toml"
    config.write_text('# a study\nmode = "isotropic"\nresolution = 40\niterations = 2\nrepair = false\n')
    rc, a, _ = smooth(cli, part, tmp_path / "a.ply", "--config", config, "--json")
    rc2, b, _ = smooth(cli, part, tmp_path / "b.ply", "--mode", "isotropic", "--resolution", 40, "--iterations", 2,
                       "--no-repair", "--json")
    assert rc == rc2 == 0
    assert (tmp_path / "a.ply").read_bytes() == (tmp_path / "b.ply").read_bytes()
    assert a["parameters"] == b["parameters"]
    assert a["parameters"]["mode"] == "isotropic" and a["parameters"]["repair"] is False
    rc, c, _ = smooth(cli, part, tmp_path / "c.ply", "--config", config, "--iterations", 1, "--json")
    assert rc == 0 and c["parameters"]["iterations"] == 1 and c["parameters"]["resolution"] == 40


@pytest.mark.parametrize("text, message", [
    ("resolutoin = 40\n", "resolutoin: not a flag of smooth"),
    ("resolution = 3\n", "resolution: --resolution: '3' is not an integer in [8, 8192], or auto"),
    ('mode = "nonsense"\n', "mode:"),
    ("[voxelize]\nband = 4\n", "only the [smooth] section applies"),
])
def test_a_bad_config_file_is_refused_naming_the_file_and_key(cli, part, tmp_path, text, message):
    config = tmp_path / "bad.toml"
    config.write_text(text)
    rc, _, err = smooth(cli, part, tmp_path / "out.ply", "--config", config)
    assert rc == 3 and str(config) in err and message in err
    assert not (tmp_path / "out.ply").exists()
    rc, _, err = smooth(cli, part, tmp_path / "out.ply", "--config", tmp_path / "missing.toml")
    assert rc == 4 and "missing.toml" in err


def test_json_records_every_parameter_and_the_version(cli, part, tmp_path):
    rc, r, _ = smooth(cli, part, tmp_path / "o.ply", "--resolution", 40, "--sigma-range", 0.5, "--iterations", 3,
                      "--target-faces", 3000, "--json")
    assert rc == 0 and r["version"] == nf.__version__
    p, resolved = r["parameters"], r["resolved"]
    assert p["resolution"] == 40 and p["sigma_range"] == 0.5 and p["iterations"] == 3 and p["target_faces"] == 3000
    assert p["mode"] == "bilateral" and p["normal_steps"] == 0 and p["length_scale"] == 0  # as given: automatic
    assert resolved["resolution"] == 40 and resolved["iterations"] == 3
    assert resolved["normal_steps"] > 0 and resolved["refit_steps"] > 0 and resolved["length_scale"] > 0
    # every option of the table that smooth takes has its key, and nothing else is there
    assert sorted(k for k in p if k != "library") == sorted(_normalflow.keywords("smooth"))
    assert "distance" in p["library"] and "decimator" in p["library"]


def toml(parameters):
    """A report's parameters as a config file (the Library tier and unset values left out)."""
    def value(v):
        return ("true" if v else "false") if isinstance(v, bool) else json.dumps(v)
    return "".join(f"{k} = {value(v)}\n" for k, v in parameters.items() if k != "library" and v is not None)


def test_a_reports_parameters_repeat_the_run_as_a_config_file(cli, part, tmp_path):
    rc, a, _ = smooth(cli, part, tmp_path / "a.ply", "--resolution", 48, "--sigma-range", 0.3, "--no-repair",
                      "--json")
    assert rc == 0
    config = tmp_path / "replay.toml"
    config.write_text(toml(a["parameters"]))
    rc, b, err = smooth(cli, part, tmp_path / "b.ply", "--config", config, "--json")
    assert rc == 0, err
    assert b["parameters"] == a["parameters"] and b["resolved"] == a["resolved"]
    assert (tmp_path / "a.ply").read_bytes() == (tmp_path / "b.ply").read_bytes()


def test_remesh_keeps_creases_and_python_gives_the_tools_result(cli, data, tmp_path):
    gt = data / "pairs_gnf" / "block_gt.ply"
    out = tmp_path / "sharp.ply"
    p = subprocess.run([cli, "remesh", str(gt), str(out), "--resolution", "64", "--json"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    report = json.loads(p.stdout.strip().splitlines()[-1])
    assert report["parameters"]["sharpen"] is True and report["sharpen"]["moved"] > 0
    mesh, rep = nf.remesh(nf.read_mesh(gt), resolution=64)
    assert (mesh.vertices == nf.read_mesh(out).vertices).all() and rep["sharpen"]["moved"] == report["sharpen"]["moved"]
    plain, _ = nf.remesh(nf.read_mesh(gt), resolution=64, sharpen=False)
    reference = nf.read_mesh(gt)
    sharp_angle = nf.compare(reference, mesh)["candidates"][0]["mean_normal_angle_deg"]
    plain_angle = nf.compare(reference, plain)["candidates"][0]["mean_normal_angle_deg"]
    assert sharp_angle < 0.6 * plain_angle, (sharp_angle, plain_angle)
    info = mesh.report()
    assert info["closed"] and info["manifold"]


def tool_help(cli):
    """Every subcommand's --help-all, by name."""
    top = subprocess.run([cli, "--help"], capture_output=True, text=True).stdout
    names = re.findall(r"^  ([a-z]+)  ", top.split("Subcommands:")[1], re.M)
    return {"": top, **{n: subprocess.run([cli, n, "--help-all"], capture_output=True, text=True).stdout
                        for n in names}}


def same_number(a, b):
    try:
        return float(a) == float(b)
    except ValueError:  # a word: auto, none
        return False


def test_the_readme_names_only_the_tools_flags_and_their_defaults(cli):
    readme = (pathlib.Path(__file__).resolve().parents[2] / "README.md").read_text()
    helps = tool_help(cli)
    flags = set().union(*(re.findall(r"--[a-z][a-z0-9-]*", h) for h in helps.values()))
    others = {"--cflags", "--libs", "--static", "--all", "--check"}  # pkg-config's and scripts/format's
    assert set(re.findall(r"--[a-z][a-z0-9-]*", readme)) - flags - others == set()
    # a synopsis' [--flag N] is the flag's default in the help of some command
    defaults = {}
    for h in helps.values():
        for flag, value in re.findall(r"^\s+(--[a-z][a-z0-9-]*) [^=\n]*=([^ \n]+)", h, re.M):
            defaults.setdefault(flag, set()).add(value)
    for flag, value in re.findall(r"\[(--[a-z][a-z0-9-]*) ([0-9.-]+)\]", readme):
        assert any(same_number(value, d) for d in defaults.get(flag, ())), f"README: [{flag} {value}]"
