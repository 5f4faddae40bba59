#!/usr/bin/env python3
"""Independent checks of `normalflow compare --report` pictures (python3 standard library only).

  check_png.py decode NORMALFLOW WORKDIR   run compare --report twice on a generated sphere and a noisy copy;
                                           decode every PNG with zlib + struct (signature, chunk CRCs, IHDR,
                                           IDAT size, filters), check sizes and that both runs gave the same bytes
  check_png.py dom NORMALFLOW WORKDIR      headless Chromium --dump-dom of index.html: every <img> loaded
  check_png.py screenshot NORMALFLOW WORKDIR   headless Chromium --screenshot of index.html: not blank

The browser modes exit 77 (ctest SKIP_RETURN_CODE) when no chromium is installed."""
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import zlib

SKIP = 77


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def decode_png(path):
    """Returns (width, height, channels, rows) with rows a list of bytes (unfiltered). Checks every CRC."""
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail(f"{path}: bad signature")
    at, idat, ihdr, types = 8, b"", None, []
    while at < len(data):
        if at + 12 > len(data):
            fail(f"{path}: truncated chunk at {at}")
        (length,) = struct.unpack(">I", data[at:at + 4])
        ctype = data[at + 4:at + 8]
        body = data[at + 8:at + 8 + length]
        (crc,) = struct.unpack(">I", data[at + 8 + length:at + 12 + length])
        if zlib.crc32(ctype + body) & 0xFFFFFFFF != crc:
            fail(f"{path}: CRC mismatch in {ctype!r}")
        types.append(ctype)
        if ctype == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif ctype == b"IDAT":
            idat += body
        at += 12 + length
    if types[0] != b"IHDR" or types[-1] != b"IEND" or b"IDAT" not in types:
        fail(f"{path}: chunk order {types}")
    w, h, depth, ctype, comp, filt, interlace = ihdr
    if depth != 8 or comp != 0 or filt != 0 or interlace != 0 or ctype not in (2, 6):
        fail(f"{path}: unsupported IHDR {ihdr}")
    ch = 3 if ctype == 2 else 4
    raw = zlib.decompress(idat)
    stride = w * ch
    if len(raw) != h * (stride + 1):
        fail(f"{path}: IDAT inflates to {len(raw)} bytes, expected {h * (stride + 1)}")
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if f == 0:  # None: nothing to undo (normalflow writes only these)
            rows.append(bytes(line))
            prev = line
            continue
        if f == 2:  # Up
            line = bytearray((x + p) & 0xFF for x, p in zip(line, prev))
            rows.append(bytes(line))
            prev = line
            continue
        for i in range(stride):
            a = line[i - ch] if i >= ch else 0
            b = prev[i]
            c = prev[i - ch] if i >= ch else 0
            if f == 0:
                p = 0
            elif f == 1:
                p = a
            elif f == 2:
                p = b
            elif f == 3:
                p = (a + b) // 2
            elif f == 4:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            else:
                fail(f"{path}: filter type {f} in row {y}")
            line[i] = (line[i] + p) & 0xFF
        rows.append(bytes(line))
        prev = line
    return w, h, ch, rows


def write_sphere_obj(path, n=40):
    """A UV sphere of radius 1 (closed, welded poles)."""
    v = [(0.0, 0.0, 1.0)]
    for i in range(1, n):
        th = math.pi * i / n
        for j in range(2 * n):
            ph = math.pi * j / n
            v.append((math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)))
    v.append((0.0, 0.0, -1.0))
    f, m = [], 2 * n
    ring = lambda i, j: 1 + (i - 1) * m + (j % m)  # 0-based index
    for j in range(m):
        f.append((0, ring(1, j), ring(1, j + 1)))
        f.append((len(v) - 1, ring(n - 1, j + 1), ring(n - 1, j)))
    for i in range(1, n - 1):
        for j in range(m):
            a, b, c, d = ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1)
            f += [(a, b, c), (a, c, d)]
    with open(path, "w") as out:
        out.writelines(f"v {x:.7f} {y:.7f} {z:.7f}\n" for x, y, z in v)
        out.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f)


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        fail(f"{' '.join(cmd)} exited {r.returncode}: {r.stdout}")
    return r.stdout


def make_report(exe, work, name="rep"):
    os.makedirs(work, exist_ok=True)
    ref, noisy = os.path.join(work, "sphere.obj"), os.path.join(work, "noisy.ply")
    if not os.path.exists(ref):
        write_sphere_obj(ref)
        run([exe, "noise", ref, noisy, "--sigma", "0.5", "--seed", "3", "-q"])
    rep = os.path.join(work, name)
    shutil.rmtree(rep, ignore_errors=True)
    run([exe, "compare", ref, noisy, ref, "--samples", "3000", "--no-self-intersections", "--report", rep, "-q"])
    return rep


def pngs(folder):
    out = []
    for root, _, files in os.walk(folder):
        out += [os.path.join(root, f) for f in files if f.endswith(".png")]
    return sorted(out)


def mode_decode(exe, work):
    a, b = make_report(exe, work, "rep1"), make_report(exe, work, "rep2")
    files = pngs(a)
    # reference + 2 candidates, 3 views, shaded + distance, + legend
    if len(files) != 3 * 3 * 2 + 1:
        fail(f"{len(files)} PNG files in {a}, expected 19: {files}")
    for p in files:
        w, h, ch, rows = decode_png(p)
        if ch != 3:
            fail(f"{p}: {ch} channels, expected RGB")
        legend = os.path.basename(p) == "legend.png"
        if (w, h) != ((400, 48) if legend else (400, 400)):
            fail(f"{p}: {w} x {h}")
        colours = {row[i:i + 3] for row in rows for i in range(0, len(row), 3)}
        if len(colours) < 3:
            fail(f"{p}: only {len(colours)} colours")
        if not legend and rows[0][:3] != b"\xff\xff\xff":
            fail(f"{p}: top-left pixel is not the white background")
        other = os.path.join(b, os.path.relpath(p, a))
        if open(p, "rb").read() != open(other, "rb").read():
            fail(f"{p} and {other} differ: output is not deterministic")
    # The pictures are named after the files: the reference sphere.obj, the candidates noisy.ply and sphere.obj.
    for name in ("reference_sphere_front.png", "noisy_side_distance.png", "sphere_oblique_distance.png"):
        if not os.path.exists(os.path.join(a, "pictures", name)):
            fail(f"no pictures/{name} in {a}: {[os.path.basename(f) for f in files]}")
    # The reference's distance picture uses only shades of the first viridis colour (68, 1, 84).
    w, h, ch, rows = decode_png(os.path.join(a, "pictures", "reference_sphere_front_distance.png"))
    for row in rows:
        for i in range(0, len(row), 3):
            r, g, bb = row[i:i + 3]
            if (r, g, bb) != (255, 255, 255) and not (g <= 2 and r <= 69 and bb <= 85 and bb > r):
                fail(f"reference distance picture has colour {(r, g, bb)}")
    html = open(os.path.join(a, "index.html"), encoding="utf-8").read()
    srcs = re.findall(r'src="([^"]+)"', html)
    if len(srcs) != 19 or any(s.startswith(("/", "http:", "https:", "file:")) for s in srcs):
        fail(f"index.html image sources: {srcs}")
    if "<link" in html or re.search(r"<script[^>]+src=", html):
        fail("index.html refers to an external resource")
    print(f"ok: {len(files)} PNG files decode, CRCs match, two runs give the same bytes")


def chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def require_chromium():
    if not chromium():
        print("SKIP: no chromium on PATH (scripts/setup installs it)")
        sys.exit(SKIP)


def browser(work, args):
    require_chromium()
    exe = chromium()
    profile = os.path.join(work, "chromium-profile")
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--hide-scrollbars",
           "--allow-file-access-from-files", "--virtual-time-budget=10000", f"--user-data-dir={profile}"] + args
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=120,
                       env=dict(os.environ, HOME=work))
    return r


def mode_dom(exe, work):
    require_chromium()
    rep = make_report(exe, work)
    url = "file://" + os.path.abspath(os.path.join(rep, "index.html"))
    r = browser(work, ["--dump-dom", url])
    dom = r.stdout
    m = re.search(r'id="image-status"[^>]*', dom)
    if not m:
        fail(f"no #image-status in the dumped DOM (chromium exit {r.returncode}): {r.stderr[-2000:]}")
    loaded = re.search(r'data-loaded="(-?\d+)"', m.group(0))
    total = re.search(r'data-total="(\d+)"', m.group(0))
    if not loaded or not total or loaded.group(1) != total.group(1) or int(total.group(1)) != 19:
        fail(f"images loaded: {m.group(0)}")
    bad = re.findall(r'<img[^>]*data-loaded="no"[^>]*>', dom)
    if bad:
        fail(f"images that did not load: {bad}")
    if len(re.findall(r'<img[^>]*data-loaded="yes"', dom)) != 19:
        fail("not every <img> is marked loaded")
    print(f"ok: chromium loaded {total.group(1)} of {total.group(1)} images")


def mode_screenshot(exe, work):
    require_chromium()
    rep = make_report(exe, work)
    url = "file://" + os.path.abspath(os.path.join(rep, "index.html"))
    shot = os.path.join(work, "screenshot.png")
    if os.path.exists(shot):
        os.remove(shot)
    r = browser(work, [f"--screenshot={shot}", "--window-size=1200,1000", url])
    if not os.path.exists(shot):
        fail(f"no screenshot (chromium exit {r.returncode}): {r.stderr[-2000:]}")
    w, h, ch, rows = decode_png(shot)
    if (w, h) != (1200, 1000):
        fail(f"screenshot is {w} x {h}")
    counts = {}
    for row in rows:
        for i in range(0, len(row), ch):
            px = row[i:i + 3]
            counts[px] = counts.get(px, 0) + 1
    background = counts.get(b"\xff\xff\xff", 0) / (w * h)
    # Shaded pictures (greys) and distance pictures (viridis): many colours, a good part not white.
    viridis = sum(n for px, n in counts.items() if px[2] > px[1] + 20 and px[2] > px[0])  # purple/blue pixels
    if len(counts) < 100 or background > 0.9 or viridis < 1000:
        fail(f"screenshot looks blank: {len(counts)} colours, {background:.0%} white, {viridis} purple-blue pixels")
    print(f"ok: screenshot {w} x {h}, {len(counts)} colours, {background:.0%} white, {viridis} purple-blue pixels")


if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[1] not in ("decode", "dom", "screenshot"):
        print(__doc__)
        sys.exit(2)
    mode, exe, work = sys.argv[1], sys.argv[2], sys.argv[3]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    {"decode": mode_decode, "dom": mode_dom, "screenshot": mode_screenshot}[mode](exe, work)
    shutil.rmtree(work, ignore_errors=True)
