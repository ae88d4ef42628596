#!/usr/bin/env bash
# Install dependencies, build everything (Release with invariant checks on) and run the whole
# test suite with CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_dependencies.sh
cmake -S . -B build-test -DCMAKE_BUILD_TYPE=Release -DPAPERSIM_ASSERTS=ON > build-test-configure.log
cmake --build build-test -j"$(nproc)"
ctest --test-dir build-test --output-on-failure -j"$(nproc)"
