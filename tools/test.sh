#!/usr/bin/env bash
# The test suite as CI runs it: install packages; every unit test and the bad-input tests first,
# with AddressSanitizer + UBSan; every input parser under libFuzzer (from the ASan build); a Release
# build with the end-to-end tests and the install checks; every test that runs threads of ours with
# ThreadSanitizer; and, in CI, the aarch64 cross build (GCC, -O3) with its unit tests under qemu.
# Each x86-64 unit test is built once, in the ASan tree; with VOCA_SANITIZERS=0 Release runs them.
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
# The cross build runs in the background from the start (see below); the cross stage, or a failing
# stage, stops it. Its package installation is never interrupted: that would leave dpkg half done.
cross_build_pid=
stop_cross_build() {
  [ -n "${cross_build_pid}" ] || return 0
  while [ ! -e build/aarch64-background.setup-done ] && kill -0 "${cross_build_pid}" 2>/dev/null; do sleep 1; done
  kill -TERM -- "-${cross_build_pid}" 2>/dev/null || true
  wait "${cross_build_pid}" 2>/dev/null || true
  cross_build_pid=
}
trap 'stop_cross_build; print_stage_times' EXIT

source tools/test_targets.sh

bash tools/setup.sh
stage_done "setup (packages)"

sanitizers=${VOCA_SANITIZERS:-1}
fuzz_seconds=${VOCA_FUZZ_SECONDS:-10}
cross=${VOCA_CROSS:-$([ "${CI:-}" = true ] && echo 1 || echo 0)}

# The aarch64 cross build (its toolchain and packages, then voca, the library and the unit tests
# the cross stage runs under qemu) starts here in the background, the build at the lowest priority:
# the stages before the cross stage leave CPU idle (the tail of a test stage where one long test
# runs alone, tests waiting on a clock or a socket), and nice 19 takes only that. The cross stage
# finishes the build at full priority. Its output: build/aarch64-background.log.
cross_targets() {
  mapfile -t cross_tests < <(test_names --preset aarch64)
  printf '%s\n' voca voca_rt
  build_targets build/aarch64 "${cross_tests[@]}"
}
if [ "${cross}" = 1 ]; then
  mkdir -p build
  rm -f build/aarch64-background.setup-done
  set -m  # the background job gets a process group of its own, which stop_cross_build ends
  (
    bash tools/cross-setup.sh aarch64
    touch build/aarch64-background.setup-done
    cmake --preset aarch64
    mapfile -t targets < <(cross_targets)
    exec nice -n 19 cmake --build --preset aarch64 --target "${targets[@]}"
  ) >build/aarch64-background.log 2>&1 &
  cross_build_pid=$!
  set +m
fi

if [ "${sanitizers}" != 0 ]; then
  # The unit tests first, so a broken build or unit fails within minutes, and each unit test built
  # once for x86-64: under AddressSanitizer + UBSan (clang; a report aborts the test), together with
  # the bad-input tests (label asan) and the fuzzers. The end-to-end tests run five to seven times
  # slower under ASan (they render and track whole sequences), so CI runs them in Release and leaves
  # their ASan run to `ctest --preset asan`, which runs every test.
  cmake --preset asan >/dev/null
  mapfile -t asan_tests < <(test_names --preset asan -L 'unit|asan')
  cmake --build --preset asan --target fuzzers $(build_targets build/asan "${asan_tests[@]}")
  stage_done "asan build (unit and bad-input tests, fuzzers)"
  ctest --preset asan -L 'unit|asan'
  stage_done "asan tests (labels unit, asan)"
fi

# Fuzz stage: every input parser under libFuzzer with ASan + UBSan, 10 s per target from the
# committed seed corpora (regression inputs included); any crash, leak or sanitizer report fails.
# VOCA_FUZZ_SECONDS changes the time per target; 0 skips the stage.
if [ "${fuzz_seconds}" != 0 ]; then
  bash tools/fuzz.sh "${fuzz_seconds}"
  stage_done "fuzz"
fi

# Release: everything a user installs, and the tests the ASan stage did not run (the end-to-end
# tests, and the unit tests a sanitizer cannot run: test_pipeline_alloc interposes malloc). Without
# the sanitizer stages, every test: the unit tests first.
cmake --preset release
if [ "${sanitizers}" != 0 ]; then
  mapfile -t release_tests < <(test_names --preset release | grep -vxF -f <(printf '%s\n' "${asan_tests[@]}"))
  cmake --build --preset release --target $(all_except_tests build/release "${asan_tests[@]}")
  stage_done "release build (all but the unit tests run under ASan)"
  ctest --preset release -R "^($(IFS='|'; echo "${release_tests[*]}"))\$"
  stage_done "release tests (end-to-end, release-only)"
else
  mapfile -t unit_tests < <(test_names --preset release -L unit)
  cmake --build --preset release --target $(build_targets build/release "${unit_tests[@]}")
  stage_done "release build (unit tests)"
  ctest --preset release -L unit
  stage_done "release unit tests"
  cmake --build --preset release
  stage_done "release build (the rest)"
  ctest --preset release -LE unit
  stage_done "release end-to-end tests"
fi
# Install stage: the installed tree (only the expected files), the CMake package and pkg-config file
# used by programs built against it alone, the example's poses against the command line's, and the
# amd64 Debian package (tools/check_install.sh).
bash tools/check_install.sh release
stage_done "install, consumers, amd64 package"

if [ "${sanitizers}" != 0 ]; then
  # ThreadSanitizer: every test labelled threads (the runtime, the decode stage, the pipeline with
  # its thread layouts and SIGINT, live replay with drops, the network source with loss, the fake
  # camera, the API, the view server and the ROS 2 sink), with the voca tool some of them run.
  cmake --preset tsan >/dev/null
  mapfile -t tsan_tests < <(test_names --preset tsan)
  cmake --build --preset tsan --target voca $(build_targets build/tsan "${tsan_tests[@]}")
  stage_done "tsan build (tests labelled threads)"
  # Their input sequences are rendered by the Release voca (VOCA_TEST_SYNTH, test::renderSynth):
  # ten times faster than under TSan, and only input there; test_synth_e2e checks the renderer's
  # own threads under TSan.
  VOCA_TEST_SYNTH="$PWD/build/release/bin/voca" ctest --preset tsan
  stage_done "tsan tests (label threads)"
fi

# Cross stage: the aarch64 build started in the background, and its unit tests under qemu-user, so
# the ARM build cannot rot unnoticed. Runs in CI (CI=true) or with VOCA_CROSS=1; VOCA_CROSS=0 skips it.
# Builds only the voca tool, the library and the unit-test executables, not the e2e tests; then
# packages the arm64 .deb and runs the example built against it under qemu.
if [ "${cross}" = 1 ]; then
  # What the background job has not finished is done at full priority (ninja keeps what it built);
  # a failure shows here.
  stop_cross_build
  bash tools/cross-setup.sh aarch64
  cmake --preset aarch64 >/dev/null
  mapfile -t targets < <(cross_targets)
  cmake --build --preset aarch64 --target "${targets[@]}"
  stage_done "cross build (the rest of it)"
  ctest --preset aarch64
  stage_done "cross emulated unit tests"
  bash tools/check_install.sh aarch64
  stage_done "arm64 package and example"
fi
