"""normalflow over a set of files with Dask (Debian python3-distributed): the same code a cluster runs, on a
LocalCluster of worker processes here. Each task reads a file, smooths it and writes the result; the results are
the ones a plain loop in this process gives, and a bad file fails its own task only."""
import pytest

distributed = pytest.importorskip("distributed")

import numpy as np  # noqa: E402

import normalflow as nf  # noqa: E402


def smooth_file(path, out, options):
    """One task: what a worker runs (imports normalflow in the worker process)."""
    import normalflow
    mesh, report = normalflow.smooth(normalflow.read_mesh(path), **options)
    normalflow.write_mesh(out, mesh)
    return {"file": str(path), "triangles": int(len(mesh.faces)), "iterations": report["smooth"]["iterations"]}


def test_a_local_cluster_smooths_files_as_a_loop_does(data, tmp_path):
    names = ["block_n0.4", "twelve_imp0.5", "fandisk_n0.3"]
    inputs = [data / "pairs_gnf" / f"{n}.ply" for n in names]
    bad = tmp_path / "broken.ply"
    bad.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n")
    options = {"resolution": 64, "threads": 1}
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        futures = [client.submit(smooth_file, p, tmp_path / f"{p.stem}_out.ply", options, pure=False)
                   for p in inputs + [bad]]
        results = [f.result() for f in futures[:-1]]
        with pytest.raises(nf.InvalidInput, match="broken.ply"):
            futures[-1].result()
        assert len({w["host"] for w in client.scheduler_info()["workers"].values()}) >= 1
        assert len(client.scheduler_info()["workers"]) == 2
    for p, r in zip(inputs, results):
        local, _ = nf.smooth(nf.read_mesh(p), **options)
        remote = nf.read_mesh(tmp_path / f"{p.stem}_out.ply")
        assert r["triangles"] == len(local.faces)
        np.testing.assert_array_equal(remote.vertices, local.vertices)


def test_a_bricked_run_on_a_local_cluster_is_the_run_here_bit_for_bit(data):
    """smooth(..., client=) runs the bricks as tasks on the workers, each worker process building the mesh's search
    once; the result is the same bricked run made here, vertex for vertex."""
    mesh = nf.read_mesh(data / "pairs_gnf" / "fandisk_n0.3.ply")
    options = {"resolution": 80, "brick_size": 32, "iterations": 2, "threads": 1, "connectivity": "remesh"}
    here, here_report = nf.smooth(mesh, **options)
    assert here_report["bricks"]["ran"] == "here"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        there, report = nf.smooth(mesh, client=client, **options)
        ran = client.run(lambda: list(__import__("normalflow")._brick_workers))
        # a run that fits whole runs here, and says so
        whole, whole_report = nf.smooth(mesh, client=client, resolution=48, threads=1)
    assert report["bricks"]["ran"] == "elsewhere"
    assert report["bricks"]["iterations"] == here_report["bricks"]["iterations"] == 2
    assert report["bricks"]["bricks_run"] == here_report["bricks"]["bricks_run"] > 8
    assert len(ran) == 2 and any(len(r) == 1 for r in ran.values()), ran  # the workers ran this run's bricks
    np.testing.assert_array_equal(there.vertices, here.vertices)
    np.testing.assert_array_equal(there.faces, here.faces)
    assert "bricks" not in whole_report
    assert any("not in bricks on the workers" in w for w in whole_report["warnings"])
    with pytest.raises(TypeError, match="Volume"):
        nf.smooth(nf.voxelize(mesh, resolution=32)[0], client=object())


def test_a_worker_refuses_a_message_it_cannot_read():
    """What a worker is sent is checked: a context or job that is not a message of this build is refused with a line
    that says which, not misread."""
    with pytest.raises(nf.InvalidInput, match="brick context"):
        nf._normalflow.BrickWorker(b"")
    with pytest.raises(nf.InvalidInput, match="brick context"):
        nf._normalflow.BrickWorker(b"\x00" + b"NFBC" + b"\x00" * 64)
