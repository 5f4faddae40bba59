"""normalflow batch: one JSON line per file, a failure kept to its file, resumable, parallel with the same
results, and the Python module's result for each file."""
import json
import shutil
import subprocess

import numpy as np
import pytest

import normalflow as nf


def batch(cli, *args):
    p = subprocess.run([cli, "batch", *map(str, args), "--json"], capture_output=True, text=True)
    lines = [json.loads(line) for line in p.stdout.splitlines() if line.startswith("{")]
    return p.returncode, [l for l in lines if "summary" not in l], lines[-1].get("summary"), p.stderr


@pytest.fixture
def folder(data, tmp_path):
    d = tmp_path / "in"
    (d / "sub").mkdir(parents=True)
    shutil.copy(data / "pairs_gnf" / "block_n0.4.ply", d / "block.ply")
    shutil.copy(data / "pairs_gnf" / "twelve_imp0.5.ply", d / "sub" / "twelve.ply")
    (d / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")  # a face with a vertex that does not exist
    (d / "notes.txt").write_text("not a mesh")
    return d


def test_a_corrupt_file_fails_alone_and_the_run_resumes(cli, folder, tmp_path):
    out = tmp_path / "out"
    rc, files, summary, _ = batch(cli, folder, "-r", "-o", out, "--resolution", 48, "--jobs", 2)
    assert rc == 1  # one file failed
    by_name = {f["file"].split("/")[-1]: f for f in files}
    assert sorted(by_name) == ["block.ply", "broken.obj", "twelve.ply"]  # notes.txt is not a mesh
    assert by_name["broken.obj"]["status"] == "failed"
    assert "broken.obj" in by_name["broken.obj"]["error"] and by_name["broken.obj"]["exit_status"] == 3
    assert by_name["block.ply"]["status"] == by_name["twelve.ply"]["status"] == "ok"
    assert summary["ok"] == 2 and summary["failed"] == 1 and summary["files"] == 3 and summary["jobs"] == 2
    assert (out / "block.ply").exists() and (out / "sub" / "twelve.ply").exists()  # folders mirrored
    assert not (out / "broken.ply").exists()
    assert sorted(p.name for p in out.rglob("*") if p.is_file()) == ["block.ply", "twelve.ply"]  # no partial file
    # each result is the Python module's (and so the tool's) for that file
    mine, _ = nf.smooth(nf.read_mesh(folder / "block.ply"), resolution=48)
    np.testing.assert_array_equal(nf.read_mesh(out / "block.ply").vertices, mine.vertices)
    assert by_name["block.ply"]["triangles"] == len(mine.faces)
    # again: the results that exist are skipped, the broken file fails again
    before = (out / "block.ply").stat().st_mtime_ns
    rc, files, summary, _ = batch(cli, folder, "-r", "-o", out, "--resolution", 48)
    assert rc == 1 and summary["skipped"] == 2 and summary["failed"] == 1 and summary["ok"] == 0
    assert (out / "block.ply").stat().st_mtime_ns == before


def test_jobs_do_not_change_results_and_a_list_works(cli, folder, tmp_path):
    (folder / "broken.obj").unlink()
    listing = tmp_path / "files.txt"
    listing.write_text(f"# two files\n{folder / 'block.ply'}\n{folder / 'sub' / 'twelve.ply'}\n")
    rc1, _, s1, _ = batch(cli, "--list", listing, "-o", tmp_path / "a", "--resolution", 40, "--jobs", 1, "--format", "obj")
    rc2, _, s2, _ = batch(cli, "--list", listing, "-o", tmp_path / "b", "--resolution", 40, "--jobs", 2, "--format", "obj")
    assert rc1 == rc2 == 0 and s1["ok"] == s2["ok"] == 2
    for name in ("block.obj", "twelve.obj"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_bad_batches_are_refused_before_any_work(cli, folder, tmp_path):
    (folder / "sub" / "block.ply").write_bytes((folder / "block.ply").read_bytes())
    p = subprocess.run([cli, "batch", str(folder / "block.ply"), str(folder / "sub" / "block.ply"), "-o",
                        str(tmp_path / "o")], capture_output=True, text=True)
    assert p.returncode == 3 and "would both be written to" in p.stderr and not (tmp_path / "o").exists()
    p = subprocess.run([cli, "batch", str(folder / "block.ply"), "-o", str(folder)], capture_output=True, text=True)
    assert p.returncode == 3 and "is an input file" in p.stderr
    p = subprocess.run([cli, "batch", str(folder / "notes.txt"), "-o", str(tmp_path / "o")], capture_output=True, text=True)
    assert p.returncode == 3 and "notes.txt: not a mesh or volume file" in p.stderr
    p = subprocess.run([cli, "batch", "--list", str(tmp_path / "missing.txt"), "-o", str(tmp_path / "o")],
                       capture_output=True, text=True)
    assert p.returncode == 4 and "missing.txt" in p.stderr


def test_a_lines_result_is_the_report_smooth_and_python_give(cli, data, tmp_path):
    part = data / "pairs_gnf" / "block_n0.4.ply"
    d = tmp_path / "one"
    d.mkdir()
    shutil.copy(part, d / "block.ply")
    rc, files, _, err = batch(cli, d, "-o", tmp_path / "out", "--resolution", 40, "--sigma-range", 0.3)
    assert rc == 0, err
    result = files[0]["result"]
    p = subprocess.run([cli, "smooth", str(part), str(tmp_path / "s.ply"), "--resolution", "40", "--sigma-range",
                        "0.3", "--json"], capture_output=True, text=True)
    tool = json.loads(p.stdout.strip().splitlines()[-1])
    _, py = nf.smooth(nf.read_mesh(part), resolution=40, sigma_range=0.3)
    for report in (tool, py):  # one shape: the pipeline's report with the command, parameters and resolved
        assert report["command"] == result["command"] == "smooth"
        assert report["parameters"] == result["parameters"] and report["resolved"] == result["resolved"]
        assert {"voxelize", "smooth", "connectivity", "checked", "version"} <= set(result) & set(report)
    assert result["output"]["triangles"] == files[0]["triangles"] == tool["output"]["triangles"]
