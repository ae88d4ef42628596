#!/usr/bin/env bash
# Fuzz the input readers with libFuzzer (clang, AddressSanitizer, UndefinedBehaviorSanitizer):
# the scene reader, the sheet OBJ and PLY readers and scenegen's mesh reader.
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     (default 60 s, every target)
# Needs Debian's clang and libclang-rt-14-dev. Each target starts from its seed corpus in
# tests/data/fuzz/<target>/ and keeps what it finds in build-fuzz/corpus/<target>/. A finding
# (crash, sanitizer report, an exception other than the reader's own error types, a leak) stops
# the script with status 1; the input is saved as build-fuzz/findings/<target>-crash-*.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_scene fuzz_sheet_obj fuzz_sheet_ply fuzz_scenegen_obj)

cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DPAPERSIM_BUILD_FUZZERS=ON \
  -DPAPERSIM_BUILD_TESTS=OFF -DPAPERSIM_BUILD_BENCHMARKS=OFF -DPAPERSIM_BUILD_VALIDATION=OFF \
  -DPAPERSIM_ASSERTS=ON > build-fuzz-configure.log
cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]}"

mkdir -p build-fuzz/findings
status=0
for t in "${targets[@]}"; do
  corpus="build-fuzz/corpus/$t"
  mkdir -p "$corpus"
  echo "fuzz: $t for $seconds s"
  if ! "build-fuzz/tests/fuzz/$t" "$corpus" "tests/data/fuzz/$t" -max_total_time="$seconds" \
      -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10 -max_len=65536 \
      -artifact_prefix="build-fuzz/findings/$t-" -print_final_stats=1 \
      > "build-fuzz/$t.log" 2>&1; then
    echo "fuzz: $t FOUND A PROBLEM (see build-fuzz/$t.log and build-fuzz/findings/)"
    tail -30 "build-fuzz/$t.log"
    status=1
  else
    grep -E "^stat::number_of_executed_units|^Done" "build-fuzz/$t.log" | tr '\n' ' '
    echo
  fi
done
exit $status
