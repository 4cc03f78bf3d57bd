#!/usr/bin/env bash
# Builds the unit tests for aarch64 with AddressSanitizer and UBSan and runs them under qemu-user.
# The aarch64 build reaches paths an x86-64 run does not: Eigen's NEON kernels fuse multiply and
# add where SSE2 does not, so the estimator can marginalise another keyframe or reset on another
# frame. A memory error on such a path stays silent in the emulated Release run of CI (the bytes
# it hits may be harmless there); here it stops the test with a report.
#
#   bash tools/asan-aarch64.sh [test...]    e.g. bash tools/asan-aarch64.sh test_backend test_backend_alloc
#
# Default: every unit test of the emulated CI run (label unit, not noemu); test_pipeline_alloc, which
# replaces malloc itself, is not built with sanitizers. Build dir build/aarch64-asan, at -O1 -g1
# (GCC's ASan + UBSan at -O2 takes over 20 min on window_optimizer.cpp). Needs
# bash tools/cross-setup.sh aarch64 and the target's sanitizer runtimes
# (apt-get install libasan8:arm64 libubsan1:arm64). LeakSanitizer is off: it stops the process's
# threads with ptrace, which qemu-user does not provide. UBSan stops at its first report.
#
# Too slow for CI: ASan under qemu runs ~100x slower than native. On a 2-core machine shared with
# other builds, the backend's two tests alone took ~30 min to build and ~35 min to run (test_backend
# 1100 s, test_backend_alloc 1400 s wall); tests/CMakeLists.txt gives such runs 40 times the native
# time limits.
set -euo pipefail
cd "$(dirname "$0")/.."
build=build/aarch64-asan

missing=()
command -v aarch64-linux-gnu-g++ >/dev/null || missing+=("g++-aarch64-linux-gnu (bash tools/cross-setup.sh aarch64)")
command -v qemu-aarch64-static >/dev/null || missing+=("qemu-user-static (bash tools/cross-setup.sh aarch64)")
for p in libasan8:arm64 libubsan1:arm64; do
  [ "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null)" = "install ok installed" ] || missing+=("$p (apt-get install $p)")
done
if [ ${#missing[@]} -gt 0 ]; then
  printf 'asan-aarch64: missing %s\n' "${missing[@]}" >&2
  exit 1
fi

launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
cmake -S . -B "$build" -G Ninja --toolchain toolchains/aarch64-linux-gnu.cmake -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DVOCA_SANITIZE=address "${launcher[@]}" >/dev/null

source tools/test_targets.sh
tests=("$@")
if [ ${#tests[@]} -eq 0 ]; then
  mapfile -t tests < <(test_names --test-dir "$build" -L unit -LE noemu)
fi
mapfile -t targets < <(build_targets "$build" "${tests[@]}")
cmake --build "$build" --target "${targets[@]}"

regex="^($(IFS='|'; echo "${tests[*]}"))\$"
export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
start=$SECONDS
status=0
ctest --test-dir "$build" -R "$regex" --output-on-failure || status=$?
echo "asan-aarch64: ${#tests[@]} test executables under qemu with ASan + UBSan in $((SECONDS - start)) s"
exit $status
