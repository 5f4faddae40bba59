#!/bin/sh
# normalflow --version names every third-party library the build links and the licence that follows.
# usage: cli_version.sh NORMALFLOW EXPECTED_LICENCE [LIBRARY ...]
set -u
bin=$1 licence=$2
shift 2
out=$("$bin" --version) || { echo "--version failed"; exit 1; }
echo "$out" | head -1 | grep -q '^normalflow [0-9][0-9.]* (normalflow.s own code: Apache-2.0)$' || { echo "bad first line: $out"; exit 1; }
echo "$out" | grep -q "^this build of the tool: $licence " || { echo "expected the tool's licence $licence:"; echo "$out"; exit 1; }
for lib in "$@"; do
  echo "$out" | grep -q "^  $lib (" || { echo "expected $lib among the linked libraries:"; echo "$out"; exit 1; }
done
for lib in CGAL TetGen OpenVDB Draco OpenMesh meshoptimizer; do  # and none it does not link
  case " $* " in *" $lib "*) ;; *) echo "$out" | grep -q "^  $lib (" && { echo "$lib listed but not built:"; echo "$out"; exit 1; } ;; esac
done
exit 0
