#!/usr/bin/env bash
# Builds the libFuzzer harnesses (tests/fuzz/, clang++ with ASan + UBSan) into
# build-fuzz/ and runs each for a bounded time, starting from its committed
# seed corpus (tests/fuzz/corpus/<target>/, replayed first: a regression that
# crashes fails at once). Fails if any fuzzer finds a crash, a sanitizer
# report, an escaping exception, a timeout (hang) or runs out of memory; the
# input is left in build-fuzz/crashes/<target>-crash-<sha1> (or -timeout-,
# -oom-, -leak-) and the command to reproduce it is printed.
#   tools/scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]
#     SECONDS_PER_TARGET  default 20; 0 only builds and replays the corpora
#     TARGET              config run_file modbus canopen operator_command foxglove (default: all)
#   FUZZ_JOBS=N  fuzzers run N at a time (default: the number of CPUs)
# New inputs go to build-fuzz/work/<target>/ (kept between local runs, never
# into the committed corpus). Installs clang and its fuzzer/sanitizer runtime
# from Debian's packages when missing (as tools/scripts/setup.sh does).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
seconds=${1:-20}
shift || true
build="$root/build-fuzz"

packages=(cmake make clang libclang-rt-14-dev libyaml-cpp-dev libeigen3-dev liblcm-dev liblcm-bin libglib2.0-dev libssl-dev
          nlohmann-json3-dev)  # the Foxglove protocol's JSON (fuzz_foxglove)
"$root/tools/scripts/install_packages.sh" fuzz "${packages[@]}"

start=$(date +%s)
CXX=clang++ cmake -S "$root/tests/fuzz" -B "$build" >/dev/null
# A harness that no longer builds is a failure, not a target to skip: the
# project's sources moved under it (a reader calling into a new file).
if ! cmake --build "$build" -j"$(nproc)" > "$build/build.log" 2>&1; then
  grep -v "^\[" "$build/build.log" | tail -30 >&2
  echo "fuzz: the harnesses do not build (full log: $build/build.log)" >&2
  exit 1
fi
echo "fuzz: built in $(( $(date +%s) - start )) s"

if [ $# -gt 0 ]; then
  targets=("$@")
else
  targets=(config run_file modbus canopen operator_command foxglove)
fi
for t in "${targets[@]}"; do
  [ -x "$build/fuzz_$t" ] || { echo "fuzz: no fuzzer $build/fuzz_$t" >&2; exit 1; }
done

mkdir -p "$build/crashes" "$build/logs"
jobs=${FUZZ_JOBS:-$(nproc)}

run_one() {
  local t=$1 work="$build/work/$1" log="$build/logs/$1.log"
  mkdir -p "$work"
  local dict=()
  [ -f "$root/tests/fuzz/$t.dict" ] && dict=(-dict="$root/tests/fuzz/$t.dict")
  # -timeout: one input taking 10 s is a hang; -rss_limit_mb: 2 GiB is a leak or a runaway allocation.
  local args=(-timeout=10 -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$build/crashes/$t-" "${dict[@]}")
  if [ "$seconds" -gt 0 ]; then
    "$build/fuzz_$t" "${args[@]}" -max_total_time="$seconds" "$work" "$root/tests/fuzz/corpus/$t" >"$log" 2>&1
  else
    "$build/fuzz_$t" "${args[@]}" -runs=0 "$root/tests/fuzz/corpus/$t" >"$log" 2>&1
  fi
}

# Runs the targets FUZZ_JOBS at a time; each one's status in $build/logs/<t>.rc.
pids=()
for t in "${targets[@]}"; do
  rm -f "$build/logs/$t.rc"
  ( set +e; run_one "$t"; echo $? >"$build/logs/$t.rc" ) &
  pids+=($!)
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do sleep 0.2; done
done
for pid in "${pids[@]}"; do wait "$pid" || true; done

failed=0
for t in "${targets[@]}"; do
  log="$build/logs/$t.log"
  rc=$(cat "$build/logs/$t.rc" 2>/dev/null || echo 99)
  runs=$(grep -o '^stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || true)
  cov=$(grep -oE '(DONE|INITED) +cov: [0-9]+ ft: [0-9]+' "$log" | tail -1 | sed -E 's/(DONE|INITED) +//' || true)
  if [ "$rc" -eq 0 ]; then
    echo "fuzz: $t ok: ${runs:-?} runs in ${seconds} s, ${cov:-no coverage line}"
  else
    failed=1
    echo "fuzz: $t FAILED (exit $rc), log $log:" >&2
    grep -E -A25 '^==[0-9]+==|ERROR: libFuzzer|runtime error|invariant broken|terminate called' "$log" | head -60 >&2 || tail -30 "$log" >&2
    art=$(grep -o 'Test unit written to .*' "$log" | head -1 | sed 's/^Test unit written to //' || true)
    echo "fuzz: $t: input ${art:-(none written)}; reproduce with: $build/fuzz_$t ${art:-<input>}" >&2
  fi
done
echo "fuzz: done in $(( $(date +%s) - start )) s"
exit $failed
