#!/usr/bin/env bash
# The test suite as CI runs it: install packages, build Release, run every test; then build the
# bad-input tests with AddressSanitizer and run those again, and fuzz every input parser briefly.
set -euo pipefail
cd "$(dirname "$0")/.."

# Each stage's wall time, printed together at the end (and on failure, up to the failing stage).
stage_times=()
stage_start=$SECONDS
stage_done() {
  stage_times+=("$(printf '%-34s %5d s' "$1" $((SECONDS - stage_start)))")
  stage_start=$SECONDS
}
print_stage_times() {
  echo "stage times (total $SECONDS s):"
  for line in "${stage_times[@]}"; do echo "  $line"; done
}
trap print_stage_times EXIT

bash tools/setup.sh
stage_done "setup (packages)"
cmake --workflow --preset test
stage_done "release build and every test"
# Install stage: the installed tree (only the expected files), the CMake package and pkg-config file
# used by programs built against it alone, the example's poses against the command line's, and the
# amd64 Debian package (tools/check_install.sh).
install_start=$SECONDS
bash tools/check_install.sh release
echo "install: installed tree, consumers and amd64 package checked in $((SECONDS - install_start)) s"
stage_done "install, consumers, amd64 package"
# The asan-labelled tests, as CTest lists them (test names are their target names); only those
# are built with the sanitizers.
cmake --preset asan >/dev/null
asan_targets=$(ctest --preset asan -N | sed -n 's/^ *Test *#[0-9]*: *//p')
if [ -n "${asan_targets}" ]; then
  cmake --build --preset asan --target ${asan_targets}
  ctest --preset asan
fi
stage_done "asan build and tests"

# Fuzz stage: every input parser under libFuzzer with ASan + UBSan, 10 s per target from the
# committed seed corpora (regression inputs included); any crash, leak or sanitizer report fails.
# VOCA_FUZZ_SECONDS changes the time per target; 0 skips the stage.
fuzz_seconds=${VOCA_FUZZ_SECONDS:-10}
if [ "${fuzz_seconds}" != 0 ]; then
  fuzz_start=$SECONDS
  bash tools/fuzz.sh "${fuzz_seconds}"
  echo "fuzz: build and runs took $((SECONDS - fuzz_start)) s"
fi
stage_done "fuzz"

# Cross stage: build for aarch64 and run the unit tests under qemu-user, so the ARM build cannot
# rot unnoticed. Runs in CI (CI=true) or with VOCA_CROSS=1; VOCA_CROSS=0 skips it. Builds only the
# voca tool, the library and the unit-test executables (test names are their target names), not the
# e2e tests; then packages the arm64 .deb and runs the example built against it under qemu.
if [ "${VOCA_CROSS:-$([ "${CI:-}" = true ] && echo 1 || echo 0)}" = 1 ]; then
  cross_start=$SECONDS
  bash tools/cross-setup.sh aarch64
  cmake --preset aarch64
  cross_targets=$(ctest --preset aarch64 -N | sed -n 's/^ *Test *#[0-9]*: *//p')
  cmake --build --preset aarch64 --target voca voca_rt ${cross_targets}
  ctest --preset aarch64
  echo "cross: aarch64 setup, build and emulated unit tests took $((SECONDS - cross_start)) s"
  stage_done "cross build and emulated tests"
  cross_package_start=$SECONDS
  bash tools/check_install.sh aarch64
  echo "cross: arm64 package and the example built against it checked in $((SECONDS - cross_package_start)) s"
  stage_done "arm64 package and example"
fi
