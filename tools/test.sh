#!/usr/bin/env bash
# README command 2: set up, build and run the whole test suite.
#   tools/test.sh            setup + build, ctest once, the Debian package built,
#                            installed and run (tools/scripts/package_check.sh),
#                            then the fuzzing step
#   tools/test.sh --soak N   setup + build, then the suite N times beside a
#                            load (stress-ng: two CPU hogs per core and a disk
#                            writer; RIGCTL_SOAK_HOG="stress-ng options" for
#                            another); failures per test at the end
# Either way a test that leaves a file in the source tree fails the run: tests
# write only into their own temporary directories.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)

soak=0
case "${1:-}" in
  --soak) soak=${2:?"--soak needs a run count"}; [[ $soak =~ ^[1-9][0-9]*$ ]] || { echo "test.sh: --soak N needs N >= 1" >&2; exit 2; } ;;
  "") ;;
  *) echo "test.sh: unknown option $1 (use --soak N)" >&2; exit 2 ;;
esac

"$root/tools/scripts/setup.sh"
cd "$root/build"
jobs=$(nproc)

# What `git status` shows before the suite; anything new afterwards was left by a test.
tree_state() { git -C "$root" status --porcelain --untracked-files=all 2>/dev/null | sort; }
before=$(tree_state)
check_tree() {
  local added
  added=$(comm -13 <(echo "$before") <(tree_state))
  if [ -n "$added" ]; then
    echo "test.sh: the test run left files in the source tree (tests must write under their own temporary directory):" >&2
    echo "$added" >&2
    return 1
  fi
}

if [ "$soak" -eq 0 ]; then
  # Each step runs whatever the one before it found: a failing test does not
  # hide what the fuzzers would have found.
  failed=()
  ctest --output-on-failure -j"$jobs" --timeout 900 || failed+=(ctest)
  check_tree || failed+=("source tree check")
  "$root/tools/scripts/package_check.sh" "$root/build" || failed+=(package)  # the .deb installed and run outside the source tree
  "$root/tools/scripts/fuzz.sh" 10 || failed+=(fuzzing)  # libFuzzer harnesses (tests/fuzz/README.md): corpus replay plus 10 s per target
  if [ ${#failed[@]} -gt 0 ]; then
    echo "test.sh: failed: ${failed[*]}" >&2
    exit 1
  fi
  exit 0
fi

# Soak: the suite beside a load at normal priority (Debian's stress-ng), as on
# a busy CI machine with builds beside the tests: by default two CPU hogs per
# core (a runnable thread waits behind two others, not one) and a disk writer
# (fsyncs and page cache pressure, which the event log's and run log's
# writers feel).
"$root/tools/scripts/install_packages.sh" soak stress-ng
read -r -a hog_options <<< "${RIGCTL_SOAK_HOG:---cpu $((2 * jobs)) --cpu-method matrixprod --hdd 1}"
hog_pid=""
stop_hog() { if [ -n "$hog_pid" ]; then kill "$hog_pid" 2>/dev/null || true; wait "$hog_pid" 2>/dev/null || true; hog_pid=""; fi; }
trap stop_hog EXIT
declare -A failures=()
failed_runs=0
for ((run = 1; run <= soak; run++)); do
  # --temp-path: the disk writer's files in the build folder, not the source tree.
  stress-ng "${hog_options[@]}" --temp-path "$root/build" --timeout 0 --quiet &
  hog_pid=$!
  start=$(date +%s)
  echo "soak run $run/$soak: ctest -j$jobs beside stress-ng ${hog_options[*]} (pid $hog_pid)"
  status=0
  ctest --output-on-failure -j"$jobs" --timeout 900 > "soak-$run.log" 2>&1 || status=$?
  stop_hog
  summary=$(grep -E "tests passed|tests failed" "soak-$run.log" | tail -1 || true)
  echo "  $summary ($(( $(date +%s) - start )) s; output in build/soak-$run.log)"
  if [ "$status" -ne 0 ]; then
    failed_runs=$((failed_runs + 1))
    # ctest lists the failed tests of its last run, one "index:name" a line.
    while IFS=: read -r _ name; do
      [ -n "$name" ] && failures[$name]=$(( ${failures[$name]:-0} + 1 ))
    done < Testing/Temporary/LastTestsFailed.log
  fi
done
check_tree
if [ "$failed_runs" -eq 0 ]; then
  echo "soak: $soak of $soak loaded runs passed, no test failed"
  exit 0
fi
echo "soak: $failed_runs of $soak loaded runs had failures; failures per test:"
for name in "${!failures[@]}"; do echo "  ${failures[$name]}/$soak  $name"; done | sort -k2
exit 1
