#!/usr/bin/env bash
# mcrecon setup: install Debian 12 packages, configure and build.
#   bash setup.sh          install + build
#   bash setup.sh demo     install + build + the report on the embedded sample scenes (demo_out/report.html)
#   bash setup.sh test     install + build + run every test (ctest)
#   bash setup.sh sanitize install + an ASan+UBSan clang build in build-asan (with the libFuzzer
#                          targets) + its ctest: unit, CLI, plugin and Python module tests under the
#                          sanitizers, a short run of every fuzz target (no Blender, no benchmarks)
set -euo pipefail
cd "$(dirname "$0")"
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}

PACKAGES=(
  cmake g++ ninja-build pkg-config
  libopenimageio-dev openimageio-tools python3-openimageio
  libopenexr-dev libdeflate-dev libopencolorio-dev
  libtbb-dev libeigen3-dev libcli11-dev nlohmann-json3-dev
  libembree-dev  # Embree 3: the light-field sample generators (samples/lightfield)
  libgtest-dev libbenchmark-dev
  pybind11-dev python3-pybind11 python3-numpy
  blender xvfb xauth
  clang libclang-rt-14-dev libfuzzer-14-dev llvm-14
  slurm-wlm munge  # py_test_farm_slurm starts a one-node Slurm cluster
  python3-matplotlib python3-opencv chromium  # mcrecon report: plots, the OpenCV peer, the page test (issue 20)
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi

if [ "${1:-build}" = sanitize ]; then
  # Its own build directory: another compiler and flags (README, "Sanitizers and fuzzing").
  SAN_DIR=${SAN_BUILD_DIR:-build-asan}
  cmake -S . -B "$SAN_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ \
    -DMCRECON_SANITIZE=address,undefined -DMCRECON_FUZZ=ON -DMCRECON_BUILD_BENCH=OFF \
    -DPython3_EXECUTABLE=/usr/bin/python3
  cmake --build "$SAN_DIR" -j "$JOBS"
  # Not the end-to-end demo nor the report over every sample scene (every filter on every
  # sample, the three 16-frame sequences included): under ASan each runs past ctest's 10 minutes
  # on 2 cores. They run in `test`; the filters and the report are sanitized here by the unit,
  # Python (py_test_report), plugin and fuzz tests.
  ctest --test-dir "$SAN_DIR" --output-on-failure -j "$JOBS" -E '^(py_test_demo|py_test_report_samples)$'
  exit 0
fi

cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3
cmake --build "$BUILD_DIR" -j "$JOBS"

case "${1:-build}" in
  build) ;;
  # The report on every sample scene: demo_out/report.html, results.json, results.csv (issue 20).
  demo) shift; "$BUILD_DIR/bin/mcrecon" report --out "${DEMO_OUT:-demo_out}" "$@" ;;
  test) ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$JOBS" ;;
  *) echo "setup: unknown action '$1' (use build, demo, test or sanitize)" >&2; exit 2 ;;
esac
