#!/usr/bin/python3
"""What the Python module adds over the tool: the same default smoothing of real pairs through `normalflow smooth`
and through normalflow.smooth, in one run, with the library's own time (the report's seconds.total) as the baseline.

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/python/bench_bindings.py ../shared/data build/apps/normalflow/normalflow
"""
import json
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import normalflow as nf

data, cli = pathlib.Path(sys.argv[1]), sys.argv[2]
models = sys.argv[3:] or ["pairs_gnf/block_n0.4.ply", "pairs_gnf/fandisk_n0.3.ply", "pairs_gnf/bunny_n0.2.ply"]
print("| model | triangles in | tool: wall | tool: library | Python: smooth() wall | Python: library | "
      "call overhead | Mesh from numpy | result arrays |")
print("|---|---|---|---|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as tmp:
    for name in models:
        path = data / name
        t = time.perf_counter()
        out = subprocess.run([cli, "smooth", str(path), f"{tmp}/cli.ply", "--json"], check=True, capture_output=True,
                             text=True).stdout
        tool_wall = time.perf_counter() - t
        tool_lib = json.loads(out.strip().splitlines()[-1])["seconds"]["total"]
        mesh = nf.read_mesh(path)
        v, f = np.array(mesh.vertices, dtype=np.float64), np.array(mesh.faces, dtype=np.int64)
        t = time.perf_counter()
        m2 = nf.Mesh(v, f)
        copy_in = time.perf_counter() - t
        t = time.perf_counter()
        result, report = nf.smooth(m2)
        py_wall = time.perf_counter() - t
        t = time.perf_counter()
        arrays = (result.vertices, result.faces, result.normals)
        views = time.perf_counter() - t
        same = np.array_equal(result.vertices, nf.read_mesh(f"{tmp}/cli.ply").vertices)
        lib = report["seconds"]["total"]
        print(f"| {name} | {len(f):,} | {tool_wall:.2f} s | {tool_lib:.2f} s | {py_wall:.2f} s | {lib:.2f} s | "
              f"{(py_wall - lib) * 1000:.1f} ms | {copy_in * 1000:.1f} ms | {views * 1e6:.0f} µs"
              f"{'' if same else ' (RESULT DIFFERS)'} |")
