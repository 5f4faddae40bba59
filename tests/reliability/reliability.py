#!/usr/bin/env python3
"""Reliability checks of the normalflow tool (issue 7), run by ctest as separate tests:

  reliability.py NORMALFLOW dirty DATA_DIR      every mesh under DATA_DIR through `smooth` in every mode
  reliability.py NORMALFLOW sigint EXAMPLE       Ctrl-C stops a long run promptly, exit 130, no file left
  reliability.py NORMALFLOW memory EXAMPLE       --max-memory refuses before allocating, exit 6, no file
  reliability.py NORMALFLOW scale                the same shape at 1e-4 and 1e5 units gives the same result
  reliability.py NORMALFLOW web EXAMPLE          smooth straight to a decimated Draco .glb
  reliability.py NORMALFLOW promises DATA CHECK  remesh and smooth of the dirty set keep their promises (CHECK:
                                                 nf_check_surface, an independent evaluator)

Each run must end in one of two ways: exit 0 with a closed manifold mesh, or a non-zero exit with
one line on stderr that names the input or output file, and no output file. A signal (crash) or
a hang (timeout) fails the test.
"""
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import time

MODES = ["isotropic", "anisotropic", "highboost", "mcf", "bilateral", "guided", "tv"]
MESH_EXT = (".obj", ".ply", ".off", ".stl", ".glb", ".gltf", ".drc")
failures = []


def fail(msg):
    failures.append(msg)
    print("FAIL:", msg, flush=True)


def run(cmd, timeout=300):
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    return p, time.time() - t0


def check_outcome(name, p, out, inp):
    if p.returncode < 0 or p.returncode in (134, 136, 139):
        fail(f"{name}: crashed (status {p.returncode}): {p.stderr.strip()[-300:]}")
        return
    leftovers = [f for f in os.listdir(os.path.dirname(out)) if os.path.basename(out) in f]
    if p.returncode == 0:
        try:
            j = json.loads(p.stdout.strip().splitlines()[-1])
        except Exception as e:  # noqa: BLE001
            fail(f"{name}: exit 0 but no JSON on the last line ({e})")
            return
        o = j.get("output", {})
        if j.get("connectivity") == "kept":
            # a kept input (open, or closed with a clean kept result: manifold, no faces intersecting) comes back as its own
            # mesh, vertices moved: the same counts, and a report of what moved them (its own faces filtered,
            # or the fit to the volume)
            i = j.get("input", {})
            if not (o.get("triangles") == i.get("triangles") and o.get("input_vertices") == i.get("vertices")
                    and ("face_filter" in j or "fit" in j)):
                fail(f"{name}: exit 0, connectivity kept, but the output is not the input's mesh: {o} / {i}")
        elif not (o.get("closed") and o.get("manifold") and o.get("triangles", 0) > 0):
            fail(f"{name}: exit 0 but the output is not a closed manifold mesh: {o}")
        if not os.path.exists(out):
            fail(f"{name}: exit 0 but no output file")
        return
    lines = [l for l in p.stderr.splitlines() if l.strip()]
    if len(lines) != 1:
        fail(f"{name}: failed with {len(lines)} stderr lines (want 1): {lines[:3]}")
    elif os.path.basename(inp) not in lines[0] and os.path.basename(out) not in lines[0]:
        fail(f"{name}: the error line names neither file: {lines[0]}")
    if leftovers:
        fail(f"{name}: failed run left files behind: {leftovers}")


def dirty(nf, data):
    files = []
    for d, _, fs in os.walk(data):
        files += [os.path.join(d, f) for f in sorted(fs) if f.lower().endswith(MESH_EXT)]
    files.sort()
    if not files:
        print(f"SKIP: no meshes under {data}")
        return
    ok = refused = 0
    with tempfile.TemporaryDirectory() as tmp:
        for i, f in enumerate(files):
            for mode in MODES:
                out = os.path.join(tmp, f"out_{i}_{mode}.ply")
                name = f"{os.path.relpath(f, data)} --mode {mode}"
                p, dt = run([nf, "smooth", f, out, "--mode", mode, "--resolution", "24", "--iterations", "1",
                             "--normal-steps", "4", "--json"])
                check_outcome(name, p, out, f)
                if p.returncode == 0:
                    ok += 1
                    os.remove(out)
                else:
                    refused += 1
                    print(f"refused: {name}: {p.stderr.strip()}")
    print(f"dirty set: {len(files)} files x {len(MODES)} modes: {ok} closed manifold outputs, {refused} clear refusals")


def promises(nf, data, checker):
    """remesh and smooth of every dirty mesh with the defaults keep what they promise, by normalflow's own check
    (the report's "checked") and by an evaluator that shares no code with it (nf_check_surface: CGAL's
    self_intersections on the file as written): a re-meshed result is closed (unless trimmed to an open input),
    manifold, without degenerate faces or intersecting faces, and has no more parts than the input without a
    warning; a kept mesh has no more intersecting pairs than the input, and none where the input is closed (auto
    keeps a closed input only where its kept result is manifold without intersections). simplify_brain runs at resolution 128 (the default, 512, takes minutes)."""
    files = sorted(os.path.join(d, f) for d, _, fs in os.walk(os.path.join(data, "dirty")) for f in fs
                   if f.lower().endswith(MESH_EXT))
    if not files:
        print(f"SKIP: no meshes under {data}/dirty")
        return
    with tempfile.TemporaryDirectory() as tmp:
        for f in files:
            extra = ["--resolution", "128"] if "simplify_brain" in f else []
            for command in ("remesh", "smooth"):
                out = os.path.join(tmp, "out.ply")
                name = f"{command} {os.path.relpath(f, data)}"
                p, dt = run([nf, command, f, out, "--json"] + extra, timeout=600)
                if p.returncode != 0:
                    fail(f"{name}: status {p.returncode}: {p.stderr.strip()[-300:]}")
                    continue
                j = json.loads(p.stdout.strip().splitlines()[-1])
                c = j.get("checked", {})
                ev = json.loads(subprocess.run([checker, out], capture_output=True, text=True,
                                               check=True).stdout.strip().splitlines()[-1])
                parts_in = j.get("components", {}).get("input")
                print(f"{name}: {dt:.1f} s, {ev['faces']} faces, {j['connectivity']}, checked {c}, "
                      f"independent {ev}", flush=True)
                if j["connectivity"] == "remeshed":
                    trimmed = "trim" in j
                    if not (c.get("manifold") and (c.get("closed") or trimmed) and c.get("degenerate_faces") == 0):
                        fail(f"{name}: the re-meshed result is not as promised: {c}")
                    if ev["self_intersecting_pairs"] != 0 or c.get("self_intersecting_pairs") != 0:
                        fail(f"{name}: intersecting faces: {ev['self_intersecting_pairs']} (independent), "
                             f"{c.get('self_intersecting_pairs')} (own)")
                    if ev["split_vertices"] != 0 or ev["degenerate_faces"] != 0:
                        fail(f"{name}: the independent check splits {ev['split_vertices']} vertices, finds "
                             f"{ev['degenerate_faces']} degenerate faces")
                    if not trimmed and ev["border_edges"] != 0:
                        fail(f"{name}: {ev['border_edges']} border edges in a closed result")
                    if parts_in is not None and c.get("components", 0) > parts_in and not any(
                            "parts, the input" in w for w in j["warnings"]):
                        fail(f"{name}: {c.get('components')} parts from an input of {parts_in}, without a word")
                else:
                    if c.get("self_intersecting_pairs", 0) > c.get("input_self_intersecting_pairs", 0):
                        fail(f"{name}: the kept mesh has more intersecting pairs than the input: {c}")
                    if c.get("flipped_faces", 0) > c.get("input_flipped_faces", 0):
                        fail(f"{name}: the kept mesh has more faces turned against the surface than the input: {c}")
                    # the kept mesh, welded as the input is for its report: no crack opened between the corners
                    # of a soup (more borders, more parts), no manifold input made non-manifold
                    i = json.loads(run([nf, "info", f, "--json"])[0].stdout.strip().splitlines()[-1])
                    o = j["output"]
                    # auto keeps a closed input only where its kept result is as clean as a re-meshed one (counted
                    # welded, as the input's corners are: the evaluator reads a soup's copies of a corner apart)
                    if i["boundary_edges"] == 0 and c.get("self_intersecting_pairs") != 0:
                        fail(f"{name}: a closed input kept with {c.get('self_intersecting_pairs')} intersecting pairs")
                    if (o["components"] > i["components"] or o["boundary_edges"] > i["boundary_edges"]
                            or (i["manifold"] and not o["manifold"])):
                        fail(f"{name}: the kept mesh came apart: {o['components']} parts, {o['boundary_edges']} "
                             f"border edges, manifold {o['manifold']}; the input {i['components']}, "
                             f"{i['boundary_edges']}, {i['manifold']}")
                os.remove(out)


def sigint(nf, example):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.ply")
        p = subprocess.Popen([nf, "smooth", example, out, "--resolution", "256", "--iterations", "50"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(2.0)
        if p.poll() is not None:
            fail(f"sigint: the run ended before the signal (status {p.returncode})")
            return
        t0 = time.time()
        p.send_signal(signal.SIGINT)
        try:
            _, err = p.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            p.kill()
            fail("sigint: still running 10 s after SIGINT")
            return
        dt = time.time() - t0
        print(f"sigint: stopped {dt:.2f} s after SIGINT with status {p.returncode}: {err.strip()}")
        if p.returncode != 130:
            fail(f"sigint: exit status {p.returncode}, want 130")
        if dt > 5:
            fail(f"sigint: took {dt:.1f} s to stop")
        if os.listdir(tmp):
            fail(f"sigint: left files: {os.listdir(tmp)}")


def memory(nf, example):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.ply")
        with open(out, "w") as f:
            f.write("precious\n")
        p, dt = run([nf, "smooth", example, out, "--resolution", "4096", "--max-memory", "64M"])
        print(f"memory: status {p.returncode} after {dt:.2f} s: {p.stderr.strip()}")
        if p.returncode != 6:
            fail(f"memory: exit status {p.returncode}, want 6 (out of memory)")
        if dt > 20:
            fail(f"memory: took {dt:.1f} s to refuse (should refuse before allocating)")
        if open(out).read() != "precious\n":
            fail("memory: the existing output file was changed")
        if sorted(os.listdir(tmp)) != ["out.ply"]:
            fail(f"memory: left files: {os.listdir(tmp)}")


def write_bumpy_sphere(path, scale):
    """A closed bumpy sphere (UV grid with poles) of radius ~scale, as OBJ."""
    n, m = 24, 48
    vs = [(0.0, 0.0, 1.0)]
    for i in range(1, n):
        th = math.pi * i / n
        for j in range(m):
            ph = 2 * math.pi * j / m
            r = 1 + 0.05 * math.sin(5 * th) * math.cos(3 * ph)
            vs.append((r * math.sin(th) * math.cos(ph), r * math.sin(th) * math.sin(ph), r * math.cos(th)))
    vs.append((0.0, 0.0, -1.0))
    fs = []
    for j in range(m):
        fs.append((0, 1 + j, 1 + (j + 1) % m))
    for i in range(n - 2):
        for j in range(m):
            a, b = 1 + i * m + j, 1 + i * m + (j + 1) % m
            c, d = a + m, b + m
            fs += [(a, c, b), (b, c, d)]
    last = len(vs) - 1
    base = 1 + (n - 2) * m
    for j in range(m):
        fs.append((base + j, last, base + (j + 1) % m))
    with open(path, "w") as f:
        for v in vs:
            f.write("v %.17g %.17g %.17g\n" % tuple(scale * c for c in v))
        for t in fs:
            f.write("f %d %d %d\n" % tuple(k + 1 for k in t))


def read_ascii_ply_vertices(path):
    with open(path) as f:
        nv = 0
        while True:
            line = f.readline().strip()
            if line.startswith("element vertex"):
                nv = int(line.split()[-1])
            if line == "end_header":
                break
        return [tuple(map(float, f.readline().split()[:3])) for _ in range(nv)]


def scale(nf):
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for s in (1e-4, 1.0, 1e5):
            inp = os.path.join(tmp, f"sphere_{s:g}.obj")
            out = os.path.join(tmp, f"out_{s:g}.ply")
            write_bumpy_sphere(inp, s)
            p, _ = run([nf, "smooth", inp, out, "--mode", "anisotropic", "--resolution", "40", "--iterations", "2",
                        "--threads", "1", "--json"])
            if p.returncode != 0:
                fail(f"scale {s:g}: status {p.returncode}: {p.stderr.strip()}")
                return
            conv = os.path.join(tmp, f"out_{s:g}_ascii.ply")
            subprocess.run([nf, "convert", out, conv, "--ascii", "-q"], check=True)
            results[s] = read_ascii_ply_vertices(conv)
    ref = results[1.0]
    for s in (1e-4, 1e5):
        v = results[s]
        if len(v) != len(ref):
            fail(f"scale {s:g}: {len(v)} vertices, {len(ref)} at scale 1")
            continue
        err = max(max(abs(a / s - b) for a, b in zip(p, q)) for p, q in zip(v, ref))
        print(f"scale {s:g}: {len(v)} vertices, max |x/s - x_1| = {err:.3g} (unit sphere)")
        if err > 1e-3:
            fail(f"scale {s:g}: result differs from scale 1 by {err:.3g} (relative)")


def web(nf, example):
    """smooth straight to a decimated, Draco-compressed .glb: the file reads back closed with <= N faces."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "part.glb")
        p, _ = run([nf, "smooth", example, out, "--resolution", "48", "--iterations", "1", "--target-faces", "3000",
                    "--position-bits", "12", "--json"])
        if p.returncode != 0:
            fail(f"web: status {p.returncode}: {p.stderr.strip()}")
            return
        j = json.loads(p.stdout.strip().splitlines()[-1])
        q, _ = run([nf, "info", out, "--json"])
        info = json.loads(q.stdout.strip().splitlines()[-1])
        print(f"web: {j['decimate']['faces_before']} -> {info['triangles']} faces, {os.path.getsize(out)} bytes, "
              f"closed={info['closed']}")
        if info["triangles"] > 3000 or not info["closed"] or info["components"] != 1:
            fail(f"web: the .glb holds {info['triangles']} faces, closed={info['closed']}")
        if j["decimate"]["hausdorff"] <= 0 or j["output"]["triangles"] != info["triangles"]:
            fail(f"web: report and file disagree: {j['decimate']} vs {info['triangles']}")


def main():
    nf, what = sys.argv[1], sys.argv[2]
    if what == "dirty":
        dirty(nf, sys.argv[3])
    elif what == "sigint":
        sigint(nf, sys.argv[3])
    elif what == "memory":
        memory(nf, sys.argv[3])
    elif what == "scale":
        scale(nf)
    elif what == "web":
        web(nf, sys.argv[3])
    elif what == "promises":
        promises(nf, sys.argv[3], sys.argv[4])
    else:
        sys.exit(f"unknown check {what}")
    if failures:
        print(f"{len(failures)} failures")
        sys.exit(1)


if __name__ == "__main__":
    main()
