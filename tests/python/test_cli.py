"""The tool's --config files and the parameters its --json records."""
import json
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
    ("resolution = 3\n", "resolution: --resolution: Value 3 not in range"),
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
    p = r["parameters"]
    assert p["resolution"] == 40 and p["sigma_range"] == 0.5 and p["iterations"] == 3 and p["target_faces"] == 3000
    assert p["mode"] == "bilateral" and p["normal_steps"] > 0 and p["refit_steps"] > 0 and p["length_scale"] > 0
    # every flag that sets an option of the pipeline has its key (--no-x as x)
    for flag in _normalflow.flag_names("smooth"):
        if flag == "--help":
            continue
        key = flag[2:].removeprefix("no-").replace("-", "_")
        assert key in p, f"{flag} is not recorded in --json's parameters"


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
