#!/usr/bin/env bash
# The test suite as CI runs it: install packages; build Release and run the fast unit tests first,
# then the end-to-end tests and the install checks; every unit test and the bad-input tests again
# with AddressSanitizer + UBSan; every test that runs threads of ours with ThreadSanitizer; every
# input parser under libFuzzer (from the ASan build); and, in CI, the aarch64 cross build with its
# unit tests under qemu.
#
# Environment: VOCA_SANITIZERS=0 skips the ASan and TSan stages, VOCA_FUZZ_SECONDS=0 the fuzz stage,
# VOCA_CROSS=0/1 the cross stage (default: on when CI=true).
set -euo pipefail
cd "$(dirname "$0")/.."

# Each stage's wall time, printed together at the end (and on failure, up to the failing stage).
stage_times=()
stage_start=$SECONDS
stage_done() {
  stage_times+=("$(printf '%-40s %5d s' "$1" $((SECONDS - stage_start)))")
  echo "== $1: $((SECONDS - stage_start)) s"
  stage_start=$SECONDS
}
print_stage_times() {
  echo "stage times (total $SECONDS s):"
  for line in "${stage_times[@]}"; do echo "  $line"; done
}
trap print_stage_times EXIT

source tools/test_targets.sh

bash tools/setup.sh
stage_done "setup (packages)"

# Release: the unit tests first, so a broken build or unit fails within minutes.
cmake --preset release
mapfile -t unit_tests < <(test_names --preset release -L unit)
cmake --build --preset release --target $(build_targets build/release "${unit_tests[@]}")
stage_done "release build (unit tests)"
ctest --preset release -L unit
stage_done "release unit tests"
cmake --build --preset release
stage_done "release build (the rest)"
ctest --preset release -LE unit
stage_done "release end-to-end tests"
# Install stage: the installed tree (only the expected files), the CMake package and pkg-config file
# used by programs built against it alone, the example's poses against the command line's, and the
# amd64 Debian package (tools/check_install.sh).
bash tools/check_install.sh release
stage_done "install, consumers, amd64 package"

if [ "${VOCA_SANITIZERS:-1}" != 0 ]; then
  # AddressSanitizer + UBSan (clang; a report aborts the test): every unit test and the bad-input
  # tests (label asan), and the fuzzers, from one build. The end-to-end tests run five to seven
  # times slower under ASan (they render and track whole sequences), so CI leaves them to
  # `ctest --preset asan`, which runs every test.
  cmake --preset asan >/dev/null
  mapfile -t asan_tests < <(test_names --preset asan -L 'unit|asan')
  cmake --build --preset asan --target fuzzers $(build_targets build/asan "${asan_tests[@]}")
  stage_done "asan build (unit and bad-input tests, fuzzers)"
  ctest --preset asan -L 'unit|asan'
  stage_done "asan tests (labels unit, asan)"
  # ThreadSanitizer: every test labelled threads (the runtime, the decode stage, the pipeline with
  # its thread layouts and SIGINT, live replay with drops, the network source with loss, the fake
  # camera, the API, the view server and the ROS 2 sink), with the voca tool some of them run.
  cmake --preset tsan >/dev/null
  mapfile -t tsan_tests < <(test_names --preset tsan)
  cmake --build --preset tsan --target voca $(build_targets build/tsan "${tsan_tests[@]}")
  stage_done "tsan build (tests labelled threads)"
  ctest --preset tsan
  stage_done "tsan tests (label threads)"
fi

# Fuzz stage: every input parser under libFuzzer with ASan + UBSan, 10 s per target from the
# committed seed corpora (regression inputs included); any crash, leak or sanitizer report fails.
# VOCA_FUZZ_SECONDS changes the time per target; 0 skips the stage.
fuzz_seconds=${VOCA_FUZZ_SECONDS:-10}
if [ "${fuzz_seconds}" != 0 ]; then
  bash tools/fuzz.sh "${fuzz_seconds}"
  stage_done "fuzz"
fi

# Cross stage: build for aarch64 and run the unit tests under qemu-user, so the ARM build cannot
# rot unnoticed. Runs in CI (CI=true) or with VOCA_CROSS=1; VOCA_CROSS=0 skips it. Builds only the
# voca tool, the library and the unit-test executables, not the e2e tests; then packages the arm64
# .deb and runs the example built against it under qemu.
if [ "${VOCA_CROSS:-$([ "${CI:-}" = true ] && echo 1 || echo 0)}" = 1 ]; then
  bash tools/cross-setup.sh aarch64
  cmake --preset aarch64
  mapfile -t cross_tests < <(test_names --preset aarch64)
  cmake --build --preset aarch64 --target voca voca_rt $(build_targets build/aarch64 "${cross_tests[@]}")
  stage_done "cross build"
  ctest --preset aarch64
  stage_done "cross emulated unit tests"
  bash tools/check_install.sh aarch64
  stage_done "arm64 package and example"
fi
