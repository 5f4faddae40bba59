"""The Python module against the command-line tool of the same build, on a real pair and on analytic cases."""
import _thread
import json
import pydoc
import subprocess
import threading
import time

import numpy as np
import pytest

import normalflow as nf
from normalflow import _normalflow
from conftest import icosphere


def run_cli(cli, *args):
    out = subprocess.run([cli, *map(str, args), "--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


# ---- the same result as the tool ----------------------------------------------------------------------------------

def test_smooth_is_the_tools_result_on_a_real_pair(cli, data, tmp_path):
    noisy = data / "pairs_gnf" / "fandisk_n0.3.ply"
    out_cli = tmp_path / "cli.ply"
    report_cli = run_cli(cli, "smooth", noisy, out_cli, "--resolution", 96, "--target-faces", 6000)
    result, report = nf.smooth(nf.read_mesh(noisy), resolution=96, target_faces=6000)
    expected = nf.read_mesh(out_cli)
    assert result.faces.shape == expected.faces.shape
    np.testing.assert_array_equal(result.faces, expected.faces)
    np.testing.assert_array_equal(result.vertices, expected.vertices)
    assert report["smooth"]["iterations"] == report_cli["smooth"]["iterations"]
    assert report["mode"] == report_cli["mode"] == "bilateral"
    assert report["version"] == nf.__version__
    assert report["decimate"]["faces_after"] <= 6000


def test_voxelize_extract_compare_noise_taubin_are_the_tools(cli, data, tmp_path):
    gt, noisy = data / "pairs_gnf" / "block_gt.ply", data / "pairs_gnf" / "block_n0.4.ply"
    # voxelize + extract
    run_cli(cli, "voxelize", gt, tmp_path / "v.vdb", "--resolution", 64)
    run_cli(cli, "extract", tmp_path / "v.vdb", tmp_path / "e.ply")
    volume, _ = nf.voxelize(nf.read_mesh(gt), resolution=64)
    extracted, report = nf.extract(volume)
    np.testing.assert_array_equal(extracted.vertices, nf.read_mesh(tmp_path / "e.ply").vertices)
    assert report["extract"]["closed"] and report["extract"]["manifold"]
    # compare: every figure of the candidate's row
    row_cli = run_cli(cli, "compare", gt, noisy)["candidates"][0]
    row = nf.compare(nf.read_mesh(gt), nf.read_mesh(noisy))["candidates"][0]
    for key in ("hausdorff", "mean_distance", "rms_distance", "mean_normal_angle_deg", "area_change", "volume_change",
                "crease_preservation", "components", "closed", "manifold", "self_intersecting_pairs"):
        assert row[key] == row_cli[key], key
    # noise and taubin
    run_cli(cli, "noise", gt, tmp_path / "n.ply", "--sigma", 0.3, "--seed", 7)
    noised, nrep = nf.noise(nf.read_mesh(gt), sigma=0.3, seed=7)
    np.testing.assert_array_equal(noised.vertices, nf.read_mesh(tmp_path / "n.ply").vertices)
    assert nrep["displaced"] > 0
    run_cli(cli, "taubin", noisy, tmp_path / "t.ply", "--iterations", 5)
    smoothed, _ = nf.taubin(nf.read_mesh(noisy), iterations=5)
    np.testing.assert_array_equal(smoothed.vertices, nf.read_mesh(tmp_path / "t.ply").vertices)


# ---- arrays in and out ---------------------------------------------------------------------------------------------

def test_numpy_in_numpy_out_smooths_a_noisy_sphere():
    v, f = icosphere(4)
    rng = np.random.default_rng(3)
    noisy = v + rng.normal(0, 0.01, v.shape) * v  # radial noise, 1% of the radius
    out, report = nf.smooth(noisy, f, resolution=64)
    r_in = np.abs(np.linalg.norm(noisy, axis=1) - 1)
    r_out = np.abs(np.linalg.norm(out.vertices, axis=1) - 1)
    assert r_out.mean() < 0.5 * r_in.mean()
    assert out.vertices.dtype == np.float32 and out.vertices.shape[1] == 3
    assert out.faces.dtype == np.uint32 and out.faces.max() < len(out.vertices)
    assert out.normals.shape == out.vertices.shape
    info = out.report()
    assert info["closed"] and info["manifold"] and info["components"] == 1 and info["triangles"] == len(out.faces)
    assert np.allclose(np.linalg.norm(out.normals, axis=1), 1, atol=1e-3)
    assert report["smooth"]["iterations"] >= 1


def test_result_arrays_are_views_of_the_mesh():
    v, f = icosphere(2)
    out, _ = nf.voxelize(v, f, resolution=32)
    mesh, _ = nf.extract(out)
    a = mesh.vertices
    assert not a.flags.owndata  # a view of the C++ vector, not a copy
    a[0, 0] = 42.0
    assert mesh.vertices[0, 0] == 42.0
    del mesh  # the view keeps its mesh alive
    assert a[0, 0] == 42.0 and a.sum() != 0


def test_input_arrays_of_any_dtype_and_attributes_are_kept_by_keep():
    v, f = icosphere(3)
    colors = np.tile(np.array([[255, 0, 0, 255]], np.uint8), (len(v), 1))
    mesh = nf.Mesh(v.astype(np.float64), f.astype(np.int32), colors=colors)
    out, report = nf.smooth(mesh, resolution=48, connectivity="keep")
    assert report["connectivity"] == "kept"
    np.testing.assert_array_equal(out.faces, f)
    np.testing.assert_array_equal(out.colors, colors)


def test_results_do_not_depend_on_threads():
    v, f = icosphere(3)
    a, _ = nf.smooth(v, f, resolution=48, threads=1)
    b, _ = nf.smooth(v, f, resolution=48, threads=2)
    np.testing.assert_array_equal(a.vertices, b.vertices)


# ---- volumes -------------------------------------------------------------------------------------------------------

def test_a_ball_mask_becomes_a_sphere(tmp_path):
    n, r = 48, 16.0
    i, j, k = np.meshgrid(*(np.arange(n),) * 3, indexing="ij")
    mask = ((i - 23.5) ** 2 + (j - 23.5) ** 2 + (k - 23.5) ** 2 <= r * r).astype(np.uint8)
    volume = nf.image_to_volume(mask, spacing=(0.5, 0.5, 0.5), origin=(10, 0, 0))
    assert volume.voxel_size == 0.5
    mesh, report = nf.smooth(volume, mode="isotropic")
    radius = np.linalg.norm(mesh.vertices - np.array([10 + 23.5 * 0.5, 23.5 * 0.5, 23.5 * 0.5]), axis=1)
    assert abs(radius.mean() - r * 0.5) < 0.1 and np.abs(radius - r * 0.5).max() < 0.25
    smoothed, _ = nf.smooth(volume, mode="isotropic", volume=True)
    assert isinstance(smoothed, nf.Volume)
    smoothed.write(tmp_path / "ball.vdb")
    again, _ = nf.extract(nf.read_volume(tmp_path / "ball.vdb"))
    np.testing.assert_allclose(again.vertices, mesh.vertices, atol=1e-4)
    dense = volume.to_dense()
    assert dense.shape == tuple(volume.dims) and dense.min() < 0 < dense.max()


# ---- progress and Ctrl-C -------------------------------------------------------------------------------------------

def test_progress_is_reported_per_stage_on_the_calling_thread():
    v, f = icosphere(3)
    calls = []
    caller = threading.get_ident()
    nf.smooth(v, f, resolution=48, progress=lambda stage, fraction: calls.append((stage, fraction, threading.get_ident())))
    stages = [c[0] for c in calls]
    assert "voxelize" in stages and "smooth" in stages
    assert all(c[2] == caller for c in calls)
    assert all(0.0 <= c[1] <= 1.0 for c in calls)
    smooth = [c[1] for c in calls if c[0] == "smooth"]
    assert smooth == sorted(smooth) and smooth[-1] == 1.0


def test_an_exception_in_the_callback_stops_the_run():
    v, f = icosphere(3)

    def fail(stage, fraction):
        if stage == "smooth" and fraction > 0:
            raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        nf.smooth(v, f, resolution=48, progress=fail)


def test_ctrl_c_cancels_a_long_run():
    v, f = icosphere(4)
    timer = threading.Timer(1.0, _thread.interrupt_main)
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        nf.smooth(v, f, resolution=160, iterations=2000)  # minutes if it ran to the end
    elapsed = time.monotonic() - start
    timer.cancel()
    assert elapsed < 30


# ---- bad input -----------------------------------------------------------------------------------------------------

def test_bad_input_is_one_clear_error():
    v, f = icosphere(1)
    with pytest.raises(nf.InvalidInput, match="faces: row 0 has index 99"):
        nf.Mesh(v, np.array([[0, 1, 99]]))
    with pytest.raises(ValueError, match=r"vertices: expected an array of shape \(n, 3\)"):
        nf.Mesh(v[:, :2], f)
    with pytest.raises(ValueError, match=r"^resolution '3' is not an integer in \[8, 8192\], or auto$"):
        nf.smooth(v, f, resolution=3)
    with pytest.raises(ValueError, match="^mode 'bilaterl' is not one of bilateral, guided, tv, anisotropic"):
        nf.smooth(v, f, mode="bilaterl")
    with pytest.raises(TypeError, match="repair: expected True or False, got str"):
        nf.smooth(v, f, repair="no")
    with pytest.raises(TypeError, match="iterations: expected an integer in .*, got bool"):
        nf.smooth(v, f, iterations=True)
    with pytest.raises(ValueError, match="faces: expected integer vertex indices, got an array of float64"):
        nf.Mesh(v, f.astype(np.float64))
    assert len(nf.Mesh(v.tolist(), f.tolist()).faces) == len(f)  # lists are arrays
    with pytest.raises(TypeError, match="unexpected keyword argument 'resolutoin'"):
        nf.smooth(v, f, resolutoin=64)
    with pytest.raises(OSError, match="no_such_file.ply"):
        nf.read_mesh("no_such_file.ply")
    with pytest.raises(ValueError, match="binary mask"):
        nf.image_to_volume(np.random.default_rng(0).random((8, 8, 8)))


def test_help_names_every_keyword_with_its_default():
    for name in ("smooth", "remesh", "voxelize", "extract"):
        fn = getattr(nf, name)
        doc = pydoc.render_doc(fn)
        keywords = _normalflow.keywords(name)
        assert keywords, name
        for k in keywords:
            assert f"{k}=" in doc, f"help(normalflow.{name}) does not name {k}"
    assert "mode='bilateral'" in nf.smooth.__doc__ and "sharpen=True" in nf.remesh.__doc__
    assert "decimator" not in _normalflow.keywords("smooth")  # the Library tier is C++ only
