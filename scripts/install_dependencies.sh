#!/usr/bin/env bash
# Installs papersim's build and run dependencies from Debian 12's packages (as root).
# A no-op when everything is already there.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libopenmesh-dev libcgal-dev libgmp-dev libmpfr-dev
  libopenvdb-dev libboost-iostreams-dev libtbb-dev libblosc-dev
  libsuitesparse-dev libopenblas0-pthread
  libopenexr-dev libpng-dev
  nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  povray gnuplot-nox fonts-dejavu-core fonts-liberation
  slurm-wlm munge  # the one-node Slurm test of the batch job arrays (scripts/slurm_cluster.sh)
  clang libclang-rt-14-dev  # the libFuzzer targets (scripts/fuzz.sh)
  clang-format  # the layout check of the C++ files (scripts/check_format.sh)
  python3  # the analysis scripts of docs/ and their self-test (scripts/adaptive_mesh_bound.py)
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all dependencies are installed"
  exit 0
fi
echo "setup: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
