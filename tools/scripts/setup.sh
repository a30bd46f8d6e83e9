#!/usr/bin/env bash
# Installs what rigctl needs from Debian's packages (only what is missing) and
# builds it. Run as root on a fresh Debian 12 machine, or as a user with the
# packages already present.
#   tools/scripts/setup.sh [--program] [--plots] [--java]
#     --program  only what building and running the program needs, and only
#                the `rigctl` target (the demo, tools/demo.sh); without it
#                the test suite's packages too, and everything is built
#     --plots    also python3-matplotlib/numpy for tools/plots/plot_run.py
#     --java     also a JDK, lcm.jar and jchart2d for tools/scripts/lcm-spy
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)

# What the program links and what builds it (CMakeLists.txt's find_package
# list; rigctl bench links Google Benchmark and Boost, diagnose Ceres).
program=(cmake g++ make pkg-config liblcm-dev liblcm-bin libglib2.0-dev libmodbus-dev libspdlog-dev
         libfmt-dev libeigen3-dev libyaml-cpp-dev libcli11-dev libnlopt-cxx-dev libceres-dev
         libboost-dev libbenchmark-dev
         libssl-dev       # libcrypto HMAC-SHA256 for operator commands
         libsystemd-dev   # sd_notify: the service's readiness and watchdog (docs/deployment.md)
         libsqlite3-dev   # the run catalog of each rig PC: one SQLite file, no server (docs/rig-health.md)
         # The Foxglove WebSocket server (foxglove/server): websocketpp, the
         # maintained header-only WebSocket library Debian ships, on
         # standalone asio; nlohmann-json for the protocol's JSON and the
         # telemetry's JSON messages and schemas.
         libwebsocketpp-dev libasio-dev nlohmann-json3-dev)
# What only the test suite needs.
tests=(libgtest-dev libgmock-dev libsocketcan-dev rt-tests iproute2 socat
       dpkg-dev         # dpkg-shlibdeps: the package check (tools/scripts/package_check.sh) builds the .deb
       systemd          # systemd-analyze: tests/system/test_systemd_units.cpp scores the units' hardening
       nodejs           # the tests' real clients (tests/node: Foxglove ws-protocol, @mcap/core), npm packages installed into the build folder
       chromium)        # the operator console's test (tests/node/console_browser.cjs): a real browser, headless, driven by puppeteer-core
only_program=0
packages=("${program[@]}")
extras=()
for arg in "$@"; do
  case "$arg" in
    --program) only_program=1 ;;
    --plots) extras+=(python3 python3-numpy python3-matplotlib) ;;
    --java) extras+=(default-jdk-headless liblcm-java libjchart2d-java) ;;
    *) echo "setup.sh: unknown option $arg" >&2; exit 2 ;;
  esac
done
[ "$only_program" -eq 1 ] || packages+=("${tests[@]}")
packages+=(${extras[@]+"${extras[@]}"})

"$root/tools/scripts/install_packages.sh" setup "${packages[@]}"

# One configuration for both commands, so the test command after the demo
# only adds the tests (the program's objects serve as they are): -O2, the
# optimisation every measurement here was made with, and no debug info (-g
# costs compile time and nothing changes at run time; for gdb configure a
# build folder of your own with -DCMAKE_BUILD_TYPE=RelWithDebInfo).
configure() {
  cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O2 -DNDEBUG" \
        -DRIGCTL_BUILD_TESTS="$1" >/dev/null
}

if [ "$only_program" -eq 1 ]; then
  # The program alone: no test packages needed to configure, only its target
  # built. A build folder the test command configured is kept as it is.
  grep -q "^RIGCTL_BUILD_TESTS:BOOL=ON" "$root/build/CMakeCache.txt" 2>/dev/null || configure OFF
  cmake --build "$root/build" -j"$(nproc)" --target rigctl
  exit 0
fi

# Debian's nodejs comes without npm (a nodejs from elsewhere may bring its own).
command -v npm >/dev/null || "$root/tools/scripts/install_packages.sh" setup npm

configure ON
cmake --build "$root/build" -j"$(nproc)"
