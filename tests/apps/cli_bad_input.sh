#!/bin/sh
# CLI bad input (issue 2): every failure exits non-zero with exactly one stderr line naming the
# file, leaves no output file behind and never damages an existing one; info --json parses.
# Usage: cli_bad_input.sh NORMALFLOW_BINARY FIXTURES_DIR REPO_ROOT
set -u
nf="$1"; fixtures="$2"; root="$3"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/nf_cli.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# expect_error NAME_IN_MESSAGE CMD...: non-zero exit, exactly one stderr line, which names the file
expect_error() {
  needle="$1"; shift
  "$@" >"$tmp/out.txt" 2>"$tmp/err.txt"; rc=$?
  [ "$rc" -ne 0 ] || fail "$*: exit status 0"
  lines=$(wc -l <"$tmp/err.txt")
  [ "$lines" -eq 1 ] || fail "$*: $lines stderr lines: $(cat "$tmp/err.txt")"
  grep -qF -- "$needle" "$tmp/err.txt" || fail "$*: stderr does not name $needle: $(cat "$tmp/err.txt")"
  echo "ok (rc $rc): $(cat "$tmp/err.txt")"
}

: >"$tmp/empty.ply"
printf '\001\377garbage\000\033bytes\n\377\376' >"$tmp/garbage.obj"
cp "$fixtures/cube_ascii.ply" "$tmp/cube.xyz"
expect_error "$tmp/missing.ply" "$nf" info "$tmp/missing.ply"
expect_error "$tmp/empty.ply" "$nf" info "$tmp/empty.ply"
expect_error "$tmp/garbage.obj" "$nf" info "$tmp/garbage.obj"
expect_error "$tmp/cube.xyz" "$nf" info "$tmp/cube.xyz"
expect_error "/nonexistent/dir/out.ply" "$nf" smooth "$root/examples/noisy_part.ply" /nonexistent/dir/out.ply \
  --resolution 32 --iterations 1
[ ! -e /nonexistent/dir ] || fail "/nonexistent/dir was created"
# an output that cannot be written is refused before any work (issue 38): at a resolution whose memory check
# would refuse the run (exit 6) or whose run would take minutes, the output's folder is what is named (exit 4)
expect_error "$tmp/nodir/out.ply" "$nf" smooth "$root/examples/noisy_part.ply" "$tmp/nodir/out.ply" --resolution 4096
[ "$rc" -eq 4 ] || fail "smooth into a missing folder: exit $rc, want 4 (refused before the memory check)"
grep -qF "does not exist" "$tmp/err.txt" || fail "missing folder: $(cat "$tmp/err.txt")"
expect_error "$tmp" "$nf" remesh "$root/examples/noisy_part.ply" "$tmp" --resolution 4096
[ "$rc" -eq 4 ] || fail "remesh into a folder: exit $rc, want 4"
cp "$fixtures/cube_ascii.ply" "$tmp/afile"
expect_error "$tmp/afile/out.ply" "$nf" convert "$fixtures/cube_ascii.ply" "$tmp/afile/out.ply"
rm -f "$tmp/afile"
# compare --correspondence: a candidate with other connectivity is refused in one line naming it
expect_error "$root/examples/noisy_part.ply" "$nf" compare "$fixtures/cube_ascii.ply" "$root/examples/noisy_part.ply" \
  --correspondence --no-self-intersections
grep -qF "candidate has" "$tmp/err.txt" || fail "compare --correspondence: no count in $(cat "$tmp/err.txt")"

# an existing output file is left byte-identical when the run fails
printf 'precious contents\n' >"$tmp/keep.ply"
cp "$tmp/keep.ply" "$tmp/keep.orig"
expect_error "$tmp/garbage.obj" "$nf" smooth "$tmp/garbage.obj" "$tmp/keep.ply" --resolution 32 --iterations 1
cmp -s "$tmp/keep.ply" "$tmp/keep.orig" || fail "existing output changed by a failed run"
extra=$(ls "$tmp" | grep -v -e '^empty.ply$' -e '^garbage.obj$' -e '^cube.xyz$' -e '^keep.ply$' -e '^keep.orig$' \
  -e '^out.txt$' -e '^err.txt$')
[ -z "$extra" ] || fail "files left behind: $extra"

# info --json: the last stdout line is a JSON object with the right counts
"$nf" info --json "$fixtures/cube_ascii.ply" >"$tmp/out.txt" 2>"$tmp/err.txt" || fail "info --json failed"
python3 - "$tmp/out.txt" <<'PY' || fail "info --json output wrong"
import json, sys
d = json.loads(open(sys.argv[1]).read().splitlines()[-1])
assert d["vertices"] == 8 and d["triangles"] == 12, d
assert d["boundary_edges"] == 0 and d["closed"] is True and d["components"] == 1, d
assert d["euler_characteristic"] == 2 and d["polygons_split"] == 6, d
PY
"$nf" info --json --repair "$fixtures/cube_ascii.ply" >"$tmp/out.txt" 2>"$tmp/err.txt" || fail "info --repair failed"
python3 - "$tmp/out.txt" <<'PY' || fail "info --repair --json output wrong"
import json, sys
d = json.loads(open(sys.argv[1]).read().splitlines()[-1])
assert d["repaired"] is True and d["repair"]["duplicates_removed"] == 0, d
assert d["triangles"] == 12 and d["closed"] is True, d
PY

# tetmesh --json: the cube's 12 triangles stay the boundary (TetGen -Y) unless --surface split
if "$nf" tetmesh --json "$fixtures/cube_ascii.ply" "$tmp/cube.vtu" >"$tmp/out.txt" 2>"$tmp/err.txt"; then
  "$nf" tetmesh --json --surface split --max-volume 0.01 "$fixtures/cube_ascii.ply" "$tmp/cube2.vtu" \
    >"$tmp/out2.txt" 2>"$tmp/err.txt" || fail "tetmesh --surface split failed: $(cat "$tmp/err.txt")"
  python3 - "$tmp/out.txt" "$tmp/out2.txt" <<'PY' || fail "tetmesh --json output wrong"
import json, sys
k = json.loads(open(sys.argv[1]).read().splitlines()[-1])
s = json.loads(open(sys.argv[2]).read().splitlines()[-1])
assert "Y" in k["switches"] and "Y" not in s["switches"], (k, s)
assert abs(k["volume"] - k["surface_volume"]) < 1e-9 * k["surface_volume"], k
assert s["tetrahedra"] > 10 * k["tetrahedra"], (k, s)
PY
  # --edge-length remeshes the surface evenly first (CGAL), the defaults switch -q.../15/150
  if "$nf" tetmesh --json --edge-length 0.5 "$fixtures/cube_ascii.ply" "$tmp/cube3.vtu" >"$tmp/out3.txt" \
    2>"$tmp/err.txt"; then
    python3 - "$tmp/out3.txt" <<'PY' || fail "tetmesh --edge-length --json output wrong"
import json, sys
r = json.loads(open(sys.argv[1]).read().splitlines()[-1])
assert r["remeshed_faces"] > 12 and "/15/150O2" in r["switches"], r
assert r["min_dihedral_deg"] >= 10, r
PY
  elif ! grep -q "needs a build with CGAL" "$tmp/err.txt"; then
    fail "tetmesh --edge-length failed: $(cat "$tmp/err.txt")"
  fi
  # option errors (CLI11 adds its "Run with --help" line): refused, naming the flag
  for bad in "--optimize 10" "--edge-length -1" "--max-dihedral 180"; do
    # shellcheck disable=SC2086
    if "$nf" tetmesh $bad "$fixtures/cube_ascii.ply" "$tmp/cube4.vtu" >"$tmp/out.txt" 2>"$tmp/err.txt"; then
      fail "tetmesh $bad: exit status 0"
    fi
    grep -qF -- "${bad%% *}" "$tmp/err.txt" || fail "tetmesh $bad: stderr does not name the flag: $(cat "$tmp/err.txt")"
  done
  [ ! -e "$tmp/cube4.vtu" ] || fail "tetmesh left an output after refusing its options"
elif ! grep -q "needs a build with TetGen" "$tmp/err.txt"; then
  fail "tetmesh failed: $(cat "$tmp/err.txt")"
fi

[ "$failures" -eq 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "all CLI bad-input checks passed"
