#!/usr/bin/env bash
# README command 2: set up, build and run the whole test suite.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/setup.sh"
cd "$root/build"
ctest --output-on-failure -j"$(nproc)" --timeout 900
"$root/tools/fuzz.sh" 10  # libFuzzer harnesses (tests/fuzz/README.md): corpus replay plus 10 s of fuzzing per target
