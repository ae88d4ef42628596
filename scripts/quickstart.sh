#!/usr/bin/env bash
# The main job on its built-in default: install dependencies, build (Release), simulate the
# pull scenario (seed 1) and render it with every ground-truth pass.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_dependencies.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPAPERSIM_BUILD_TESTS=OFF > build-configure.log
cmake --build build -j"$(nproc)" --target papersim scenegen
OUT=${OUT:-out/quickstart}
./build/simulation/papersim scenario pull --seed 1 --out "$OUT/sim"
./build/scenegen/scenegen render "$OUT/sim/sheet.obj" --out "$OUT/render" --seed 1 --quality draft
echo "quickstart: simulated sheet in $OUT/sim, rendered sample in $OUT/render"
