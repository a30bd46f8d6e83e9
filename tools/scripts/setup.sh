#!/usr/bin/env bash
# Installs what rigctl needs from Debian's packages (only what is missing) and
# builds it. Run as root on a fresh Debian 12 machine, or as a user with the
# packages already present.
#   tools/scripts/setup.sh [--plots] [--java]
#     --plots  also python3-matplotlib/numpy for tools/plots/plot_run.py
#     --java   also a JDK, lcm.jar and jchart2d for tools/scripts/lcm-spy
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)

packages=(cmake g++ make pkg-config liblcm-dev liblcm-bin libglib2.0-dev libmodbus-dev libspdlog-dev
          libfmt-dev libeigen3-dev libgtest-dev libgmock-dev libsocketcan-dev libyaml-cpp-dev libcli11-dev libnlopt-cxx-dev libceres-dev
          libboost-dev libbenchmark-dev rt-tests iproute2 socat
          libssl-dev   # libssl-dev: libcrypto HMAC-SHA256 for operator commands
          libsystemd-dev   # sd_notify: the service's readiness and watchdog (docs/deployment.md)
          libsqlite3-dev   # the run catalog of each rig PC: one SQLite file, no server (docs/rig-health.md)
          systemd          # systemd-analyze: tests/system/test_systemd_units.cpp scores the units' hardening
          # The Foxglove WebSocket server (foxglove/server): websocketpp, the
          # maintained header-only WebSocket library Debian ships, on
          # standalone asio; nlohmann-json for the protocol's JSON and the
          # telemetry's JSON messages and schemas.
          libwebsocketpp-dev libasio-dev nlohmann-json3-dev
          nodejs           # the tests' real clients (tests/node: Foxglove ws-protocol, @mcap/core), npm packages installed into the build folder
          chromium)        # the operator console's test (tests/node/console_browser.cjs): a real browser, headless, driven by puppeteer-core
for arg in "$@"; do
  case "$arg" in
    --plots) packages+=(python3 python3-numpy python3-matplotlib) ;;
    --java) packages+=(default-jdk-headless liblcm-java libjchart2d-java) ;;
    *) echo "setup.sh: unknown option $arg" >&2; exit 2 ;;
  esac
done

"$root/tools/scripts/install_packages.sh" setup "${packages[@]}"
# Debian's nodejs comes without npm (a nodejs from elsewhere may bring its own).
command -v npm >/dev/null || "$root/tools/scripts/install_packages.sh" setup npm

cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$root/build" -j"$(nproc)"
