"""Fixtures of the Python tests: the normalflow tool of the same build (NORMALFLOW_CLI), the shared test meshes
(NORMALFLOW_TEST_DATA) and analytic meshes made with numpy."""
import os
import pathlib

import numpy as np
import pytest


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("NORMALFLOW_CLI")
    if not path or not os.path.exists(path):
        pytest.skip("NORMALFLOW_CLI does not name the normalflow tool")
    return path


@pytest.fixture(scope="session")
def data():
    path = pathlib.Path(os.environ.get("NORMALFLOW_TEST_DATA", "../shared/data"))
    if not (path / "pairs_gnf").is_dir():
        pytest.skip(f"no shared test data at {path}")
    return path


def icosphere(subdivisions=3, radius=1.0):
    """A unit icosphere (vertices, faces) by midpoint subdivision, projected onto the sphere."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    verts = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        cache, faces = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                cache[key] = len(verts) - 1
            return cache[key]

        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = faces
    return np.array(verts) * radius, np.array(f, dtype=np.int64)
