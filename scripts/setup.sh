#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine: installs what is missing, builds, then
#   setup.sh demo   -> runs `pmstream demo`
#   setup.sh test   -> runs the test suite (the layering check, a release build, an ASan+UBSan build of the
#                      unit tests, then short runs of every fuzz target)
#   setup.sh build  -> only builds (build/pmstream)
set -euo pipefail
cd "$(dirname "$0")/.."

mode=${1:-build}
shift || true
jobs=$(nproc 2>/dev/null || echo 2)

packages=(build-essential cmake ninja-build pkg-config git xz-utils
          libcli11-dev nlohmann-json3-dev libfmt-dev libassimp-dev zlib1g-dev liblzma-dev libxxhash-dev
          libfast-float-dev libzstd-dev libboost-dev libstb-dev libpng-dev
          libgtest-dev libgmock-dev libbenchmark-dev clang libclang-rt-14-dev
          libopenmesh-apps gnuplot-nox graphviz)

install_packages() {
  local missing=()
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "setup: installing ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  # apt may be busy with another process at boot: wait for the dpkg lock instead of failing.
  for attempt in $(seq 1 30); do
    if $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}"; then
      return 0
    fi
    echo "setup: apt busy or failed (attempt $attempt), retrying in 10 s"
    sleep 10
  done
  echo "setup: could not install ${missing[*]}" >&2
  exit 1
}

configure_and_build() {  # dir, extra cmake args...
  local dir=$1; shift
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DPMSTREAM_WERROR=ON "$@" >/dev/null
  cmake --build "$dir" -j "$jobs"
}

install_packages
case "$mode" in
  build)
    configure_and_build build
    ;;
  demo)
    configure_and_build build
    ./build/pmstream demo "$@"
    ;;
  test)
    # First, before anything builds: no include goes up or sideways in the layers (docs/architecture.md).
    bash scripts/check_layers.sh
    configure_and_build build
    (cd build && ctest --output-on-failure -j "$jobs" --timeout 900)
    # Second configuration (clang): the unit tests under AddressSanitizer + UndefinedBehaviorSanitizer, and
    # every decoder's libFuzzer target, from one build of the libraries.
    CC=clang CXX=clang++ configure_and_build build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPMSTREAM_SANITIZE=ON \
      -DPMSTREAM_FUZZ=ON
    (cd build-asan && ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j "$jobs" --timeout 900 -LE slow)
    for target in build-asan/fuzz_*; do
      [ -x "$target" ] || continue
      echo "fuzz: $(basename "$target") for ${PMSTREAM_FUZZ_SECONDS:-30} s"
      "$target" -max_total_time="${PMSTREAM_FUZZ_SECONDS:-30}" -max_len=65536 -print_final_stats=1 2>&1 | tail -3
      [ "${PIPESTATUS[0]}" -eq 0 ] || { echo "fuzz: $(basename "$target") found a failure" >&2; exit 1; }
    done
    ;;
  *)
    echo "usage: scripts/setup.sh [build|demo|test]" >&2
    exit 2
    ;;
esac
