# Sourced by scripts/sanitize and scripts/fuzz: the one instrumented build both use (build-asan).
# clang, AddressSanitizer + UBSan on every target (libraries included, so findings point at our code), and
# libFuzzer's coverage on the readers (NORMALFLOW_BUILD_FUZZERS), so that the same objects serve the libFuzzer
# targets: the libraries are compiled once for the sanitized tests and the fuzzers. -O1 (ASan's usual level): a
# third less compile time than -O3; the engine alone at -O2 (NORMALFLOW_CORE_FLAGS), where the sanitized engine
# tests spend their time. No debug information (a fifth more compile time): reports name functions; for line
# numbers, reconfigure with -DCMAKE_CXX_FLAGS=-gline-tables-only.
# No Python module: an instrumented extension cannot load into an uninstrumented interpreter (the ordinary
# suite runs tests/python).
# Usage: instrumented_build ROOT [ninja targets...]   (no targets: everything)
instrumented_build() {
  local root=$1
  shift
  local dir="$root/build-asan"
  "$root/scripts/setup" clang libclang-rt-14-dev   # libFuzzer and the sanitizer runtimes ship in clang's
  if [[ -f "$dir/CMakeCache.txt" ]] && ! grep -q '^CMAKE_CXX_COMPILER:.*clang' "$dir/CMakeCache.txt"; then
    echo "instrumented build: $dir was configured with another compiler; starting it again"
    rm -rf "$dir"
  fi
  if [[ ! -f "$dir/CMakeCache.txt" ]]; then
    local generator=()
    command -v ninja >/dev/null && generator=(-G Ninja)
    CC=clang CXX=clang++ cmake -S "$root" -B "$dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_C_FLAGS_RELEASE="-O1 -DNDEBUG" -DCMAKE_CXX_FLAGS_RELEASE="-O1 -DNDEBUG" \
      -DNORMALFLOW_CORE_FLAGS=-O2 -DNORMALFLOW_SANITIZE=ON -DNORMALFLOW_BUILD_FUZZERS=ON -DNORMALFLOW_BUILD_TESTS=ON \
      -DNORMALFLOW_BUILD_BENCHMARKS=OFF -DNORMALFLOW_BUILD_PYTHON=OFF >/dev/null
  fi
  local targets=()
  [[ $# -gt 0 ]] && targets=(--target "$@")
  cmake --build "$dir" -j "${JOBS:-$(nproc)}" "${targets[@]}"
}
