#!/usr/bin/env bash
# Fuzz the input readers with libFuzzer (clang, AddressSanitizer, UndefinedBehaviorSanitizer):
# the scene reader, the sheet OBJ and PLY readers, scenegen's mesh reader, the checkpoint
# reader with the run it continues, and dataset-stats' manifest reader against a plain parse.
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     (default 60 s, every target)
# Targets: fuzz_scene fuzz_sheet_obj fuzz_sheet_ply fuzz_scenegen_obj fuzz_checkpoint
# fuzz_dataset_stats
# (tests/fuzz/). They run one after another on one core. Needs Debian's clang and libclang-rt-14-dev
# (scripts/install_dependencies.sh installs them); the build goes to build-fuzz/ (configure log
# in build-fuzz/configure.log). Each target starts from its seed corpus in
# tests/data/fuzz/<target>/ and from what earlier runs kept in build-fuzz/corpus/<target>/, and
# adds what it finds there. Per target the script prints libFuzzer's last status line
# (executions, coverage "cov", features "ft", corpus size) and its final statistics; the full
# log is build-fuzz/<target>.log.
# Exit status: 0 when no target found anything; 1 when one did (crash, sanitizer report, an
# exception other than the reader's own error types, a leak, an input slower than 10 s, more
# than 2 GB), the input saved as build-fuzz/findings/<target>-<kind>-<hash>; 2 on bad arguments
# or a missing compiler. Callable from anywhere (it works in the repository it lives in).
set -euo pipefail
cd "$(dirname "$0")/.."
all_targets=(fuzz_scene fuzz_sheet_obj fuzz_sheet_ply fuzz_scenegen_obj fuzz_checkpoint fuzz_dataset_stats)
seconds="${1:-60}"
if [ $# -gt 0 ]; then shift; fi
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=("${all_targets[@]}")

if ! [[ "$seconds" =~ ^[1-9][0-9]*$ ]]; then
  echo "fuzz.sh: SECONDS_PER_TARGET must be a positive whole number of seconds, got '$seconds'" >&2
  exit 2
fi
for t in "${targets[@]}"; do
  if [[ " ${all_targets[*]} " != *" $t "* ]]; then
    echo "fuzz.sh: unknown target '$t' (known: ${all_targets[*]})" >&2
    exit 2
  fi
done
if ! command -v clang++ > /dev/null || \
   ! compgen -G "/usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a" > /dev/null; then
  echo "fuzz.sh: needs clang++ and libFuzzer: apt-get install clang libclang-rt-14-dev" >&2
  exit 2
fi

mkdir -p build-fuzz
if ! cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DPAPERSIM_BUILD_FUZZERS=ON \
    -DPAPERSIM_BUILD_TESTS=OFF -DPAPERSIM_BUILD_BENCHMARKS=OFF -DPAPERSIM_BUILD_VALIDATION=OFF \
    -DPAPERSIM_ASSERTS=ON > build-fuzz/configure.log 2>&1; then
  tail -20 build-fuzz/configure.log >&2
  exit 2
fi
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
    echo "  $(grep -E '^#[0-9]+' "build-fuzz/$t.log" | tail -1)"
    echo "  $(grep -E '^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)' \
      "build-fuzz/$t.log" | tr '\n' ' ')"
  fi
done
exit $status
