#!/usr/bin/env python3
"""Generates examples/noisy_part.ply: a small mechanical part made by normalflow's authors, free to ship.

The part is an assembly of closed, finely triangulated components that overlap (a base plate, an upright
web and a cylindrical boss), as CAD exports often are: a polygon soup whose union is the solid. Each
component gets Gaussian noise along its vertex normals with sigma = 0.25 x its mean edge length (the
definition the mesh-denoising literature uses), from a fixed seed, so the file is reproducible.
Pure Python (no numpy): run `python3 scripts/make_example.py examples/noisy_part.ply`.
"""
import math
import random
import struct
import sys


def box(x0, y0, z0, x1, y1, z1, step):
    """Closed box with each face split into a grid of about `step` spacing (outward CCW)."""
    verts, faces, index = [], [], {}

    def vid(p):
        key = tuple(round(c, 9) for c in p)
        if key not in index:
            index[key] = len(verts)
            verts.append(p)
        return index[key]

    lo, hi = (x0, y0, z0), (x1, y1, z1)
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        nu = max(1, round((hi[u] - lo[u]) / step))
        nv = max(1, round((hi[v] - lo[v]) / step))
        for side in (0, 1):
            w = hi[axis] if side else lo[axis]
            for i in range(nu):
                for j in range(nv):
                    quad = []
                    for (a, b) in ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)):
                        p = [0.0, 0.0, 0.0]
                        p[axis] = w
                        p[u] = lo[u] + (hi[u] - lo[u]) * a / nu
                        p[v] = lo[v] + (hi[v] - lo[v]) * b / nv
                        quad.append(vid(tuple(p)))
                    if side == 0:
                        quad.reverse()
                    faces.append((quad[0], quad[1], quad[2]))
                    faces.append((quad[0], quad[2], quad[3]))
    return verts, faces


def cylinder(cx, cy, z0, z1, r, step):
    """Closed z-aligned cylinder, caps fanned to a centre ring grid (outward CCW)."""
    n = max(8, round(2 * math.pi * r / step))
    m = max(1, round((z1 - z0) / step))
    rings = max(1, round(r / step))
    verts, faces = [], []
    side = []
    for k in range(m + 1):
        z = z0 + (z1 - z0) * k / m
        side.append([])
        for i in range(n):
            a = 2 * math.pi * i / n
            side[k].append(len(verts))
            verts.append((cx + r * math.cos(a), cy + r * math.sin(a), z))
    for k in range(m):
        for i in range(n):
            a, b = side[k][i], side[k][(i + 1) % n]
            c, d = side[k + 1][(i + 1) % n], side[k + 1][i]
            faces += [(a, b, c), (a, c, d)]
    for cap, z, outer in ((0, z0, side[0]), (1, z1, side[m])):
        prev = outer
        for q in range(rings - 1, 0, -1):
            rr = r * q / rings
            ring = []
            for i in range(n):
                a = 2 * math.pi * i / n
                ring.append(len(verts))
                verts.append((cx + rr * math.cos(a), cy + rr * math.sin(a), z))
            for i in range(n):
                a, b, c, d = prev[i], prev[(i + 1) % n], ring[(i + 1) % n], ring[i]
                tri1, tri2 = (a, b, c), (a, c, d)
                if cap == 0:
                    tri1, tri2 = tri1[::-1], tri2[::-1]
                faces += [tri1, tri2]
            prev = ring
        centre = len(verts)
        verts.append((cx, cy, z))
        for i in range(n):
            t = (prev[i], prev[(i + 1) % n], centre)
            faces.append(t if cap == 1 else t[::-1])
    return verts, faces


def add_noise(verts, faces, rng, level):
    normals = [[0.0, 0.0, 0.0] for _ in verts]
    edge_sum, edge_n = 0.0, 0
    for a, b, c in faces:
        pa, pb, pc = verts[a], verts[b], verts[c]
        e1 = [pb[i] - pa[i] for i in range(3)]
        e2 = [pc[i] - pa[i] for i in range(3)]
        n = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        for v in (a, b, c):
            for i in range(3):
                normals[v][i] += n[i]
        for p, q in ((pa, pb), (pb, pc), (pc, pa)):
            edge_sum += math.dist(p, q)
            edge_n += 1
    sigma = level * edge_sum / edge_n
    out = []
    for p, n in zip(verts, normals):
        ln = math.sqrt(sum(c * c for c in n)) or 1.0
        d = rng.gauss(0.0, sigma)
        out.append(tuple(p[i] + d * n[i] / ln for i in range(3)))
    return out


def main(path):
    rng = random.Random(20031001)
    step = 0.05
    parts = [
        box(0.0, 0.0, 0.0, 2.0, 1.2, 0.3, step),        # base plate
        box(0.0, 0.0, 0.0, 0.3, 1.2, 1.4, step),        # upright web
        cylinder(1.3, 0.6, 0.1, 0.75, 0.3, step),        # boss through the plate
    ]
    verts, faces = [], []
    for v, f in parts:
        v = add_noise(v, f, rng, 0.25)
        base = len(verts)
        verts += v
        faces += [(a + base, b + base, c + base) for a, b, c in f]
    with open(path, "wb") as out:
        out.write(("ply\nformat binary_little_endian 1.0\ncomment normalflow example: noisy mechanical part "
                   "(generated by scripts/make_example.py, CC0)\nelement vertex %d\nproperty float x\nproperty float y\n"
                   "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n"
                   % (len(verts), len(faces))).encode())
        for p in verts:
            out.write(struct.pack("<3f", *p))
        for f in faces:
            out.write(struct.pack("<B3i", 3, *f))
    print("%s: %d vertices, %d triangles" % (path, len(verts), len(faces)))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "examples/noisy_part.ply")
