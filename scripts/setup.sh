#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine: installs what is missing (apt; the page's npm packages,
# pinned by web/package-lock.json), builds, then
#   setup.sh demo   -> installs and builds what the demo needs alone (build/pmstream and the browser page's
#                      site, build/web; not the tests' packages, chromium and clang among them) and runs
#                      `pmstream demo`: on a terminal it serves the page and prints its link
#   setup.sh test   -> runs the test suite (the layering check, a release build and its tests, the browser
#                      tests included, then one clang build with ASan+UBSan: the native tests again and
#                      short runs of every fuzz target)
#   setup.sh build  -> only builds (build/pmstream, build/pmstream-bench, the tests and the page)
set -euo pipefail
cd "$(dirname "$0")/.."

mode=${1:-build}
shift || true
jobs=$(nproc 2>/dev/null || echo 2)

# What pmstream and the page build from: all the demo installs.
packages=(build-essential cmake ninja-build pkg-config git xz-utils
          libcli11-dev nlohmann-json3-dev libfmt-dev libassimp-dev zlib1g-dev liblzma-dev libxxhash-dev
          libfast-float-dev libzstd-dev libboost-dev libstb-dev libpng-dev
          libmeshoptimizer-dev libdraco-dev
          emscripten)  # the browser viewer's WASM core (web/CMakeLists.txt)
# What the tests and the bench add (chromium and clang are most of a fresh machine's download).
test_packages=(libgtest-dev libgmock-dev libbenchmark-dev clang libclang-rt-14-dev
               libopenmesh-apps gnuplot-nox graphviz
               nginx-light  # the caching proxy of deploy/nginx, which the NginxCache tests run on loopback
               haproxy      # deploy/haproxy in front of two origins: the HaproxyFailover test, the failover bench
               chromium)    # the browser tests' browser, driven headless by playwright-core (docs/web.md)
[ "$mode" = demo ] || packages+=("${test_packages[@]}")
# node and npm install the page's packages and run the browser tests. Debian's `npm` package conflicts with
# a nodejs from elsewhere (NodeSource's bundles npm), so they are asked for only when the commands are missing.
command -v node >/dev/null 2>&1 || packages+=(nodejs)
command -v npm >/dev/null 2>&1 || packages+=(npm)

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

# three.js and playwright-core, exactly as web/package-lock.json pins them, into web/node_modules; the build
# copies the page's share of them into build/web. Skipped when that install is newer than the lock file.
install_web_packages() {
  [ -f web/package-lock.json ] || return 0
  if [ -f web/node_modules/.package-lock.json ] && [ web/node_modules/.package-lock.json -nt web/package-lock.json ]; then
    return 0
  fi
  echo "setup: npm ci in web/"
  (cd web && npm ci --no-audit --no-fund --loglevel=error)
}

# The targets configure_and_build builds; empty: all of them.
targets=()

# The build's targets among $2...: the browser site's exist only when emscripten and web/node_modules do.
existing_targets() {  # dir, names...
  local dir=$1; shift
  local all
  all=$(ninja -C "$dir" -t targets all 2>/dev/null)
  for name in "$@"; do
    if grep -q "^$name: " <<<"$all"; then echo "$name"; fi
  done
}

configure_and_build() {  # dir, extra cmake args...
  local dir=$1; shift
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DPMSTREAM_WERROR=ON "$@" >/dev/null
  cmake --build "$dir" -j "$jobs" ${targets[@]+--target "${targets[@]}"}
}

# Every libFuzzer target in $1 for PMSTREAM_FUZZ_SECONDS (10) each, $jobs at a time (each is single-threaded);
# fails if one finds a crash, and prints each one's final stats.
run_fuzzers() {
  local seconds=${PMSTREAM_FUZZ_SECONDS:-10} logs failed=0
  logs=$(mktemp -d)
  for target in "$1"/fuzz_*; do
    if [[ -f "$target" && -x "$target" && "$target" != *.* ]]; then echo "$target"; fi
  done | xargs -P "$jobs" -I{} sh -c \
    '"$1" -max_total_time="$2" -max_len=65536 -print_final_stats=1 >"$3/$(basename "$1").log" 2>&1' \
    _ {} "$seconds" "$logs" || failed=1
  for log in "$logs"/*.log; do
    echo "fuzz: $(basename "$log" .log), $seconds s:"
    tail -3 "$log"
  done
  if [ "$failed" -ne 0 ]; then
    grep -l -E "ERROR: (libFuzzer|AddressSanitizer)|runtime error|SUMMARY" "$logs"/*.log | while read -r log; do
      echo "fuzz: $(basename "$log" .log) found a failure:" >&2
      grep -A30 -E "ERROR|runtime error" "$log" | head -60 >&2
    done
    exit 1
  fi
}

install_packages
install_web_packages
case "$mode" in
  build)
    configure_and_build build -DPMSTREAM_TESTS=ON
    ;;
  demo)
    # Neither the bench nor the tests: the binary and the page's site (the WASM core and the page's files).
    # The tests are not configured either: GoogleTest is among what only they install.
    cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DPMSTREAM_WERROR=ON -DPMSTREAM_TESTS=OFF >/dev/null
    mapfile -t targets < <(echo pmstream; existing_targets build web web_page)
    configure_and_build build -DPMSTREAM_TESTS=OFF
    ./build/pmstream demo "$@"
    ;;
  test)
    # First, before anything builds: no include goes up or sideways in the layers (docs/architecture.md).
    bash scripts/check_layers.sh
    configure_and_build build -DPMSTREAM_TESTS=ON
    # Every test, the browser ones (labels browser and web: node, chromium, the built site) among them.
    (cd build && ctest --output-on-failure -j "$jobs" --timeout 900)
    # Second configuration (clang): the native unit tests under AddressSanitizer + UndefinedBehaviorSanitizer,
    # and every decoder's libFuzzer target, from one build of the libraries. The browser's part was tested
    # above; it is neither built nor run again here.
    CC=clang CXX=clang++ configure_and_build build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPMSTREAM_SANITIZE=ON \
      -DPMSTREAM_FUZZ=ON -DPMSTREAM_WEB=OFF -DPMSTREAM_TESTS=ON
    (cd build-asan && ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j "$jobs" --timeout 900 -LE 'slow|browser|web')
    run_fuzzers build-asan
    ;;
  *)
    echo "usage: scripts/setup.sh [build|demo|test]" >&2
    exit 2
    ;;
esac
