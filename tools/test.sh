#!/usr/bin/env bash
# The test suite as CI runs it: install packages, build Release, run every test; then build the
# bad-input tests with AddressSanitizer and run those again.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake --workflow --preset test
if grep -rqs "LABELS asan" tests/*.cmake; then
  cmake --preset asan >/dev/null
  asan_targets=$(sed -n 's/^voca_add_test(\([a-z0-9_]*\) .*LABELS asan.*/\1/p' tests/*.cmake)
  cmake --build --preset asan --target ${asan_targets}
  ctest --preset asan
fi
