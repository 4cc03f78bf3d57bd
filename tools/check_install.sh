#!/usr/bin/env bash
# Checks what users get of VOCA-RT: the installed tree and the Debian package, each used by a program
# built against it alone (examples/odometry), whose poses must be those of the `voca` command line.
#
#   bash tools/check_install.sh [release]   after building voca and voca_rt in build/release:
#       installs into a temporary prefix (only the expected files), builds the example against that
#       prefix (find_package) and a one-file consumer through pkg-config, compares the example's rows
#       with `voca run --out` on an encoded micro EuRoC byte for byte, then builds the amd64 .deb
#       and runs the voca tool unpacked from it.
#   bash tools/check_install.sh aarch64     after building voca and voca_rt in build/aarch64 (and
#       build/release's voca for the reference): builds the arm64 .deb, unpacks it into a folder,
#       cross-builds the example against it, runs it under qemu-user on the KITTI 06 clip and
#       compares its rows with the amd64 command line's (within 1e-6: see compare_rows_within).
#
# Needs ../shared/data beside the checkout. Leaves the .deb in build/<preset>/.
set -euo pipefail
cd "$(dirname "$0")/.."
preset=${1:-release}
case "$preset" in
  release | aarch64) ;;
  *) echo "check_install: unknown preset '$preset' (expected release or aarch64)" >&2; exit 2 ;;
esac
data=${VOCA_SHARED_DATA:-../shared/data}
host_voca=build/release/bin/voca
for f in "build/$preset/bin/voca" "build/$preset/lib/libvoca-rt.so" "$host_voca"; do
  [ -e "$f" ] || { echo "check_install: $f missing: build voca and voca_rt with the $preset preset first" >&2; exit 1; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "check_install: $*" >&2; exit 1; }
# Runs a command with its output kept in a log, shown only when it fails.
quiet() { "$@" >"$work/command.log" 2>&1 || { cat "$work/command.log" >&2; fail "failed: $*"; }; }
version=$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "build/$preset/CMakeCache.txt")
libdir=$(sed -n 's/^CMAKE_INSTALL_LIBDIR:PATH=//p' "build/$preset/CMakeCache.txt")
major=${version%%.*}

# The example's rows (file $1) against the trajectory `voca run` wrote ($2), byte for byte.
compare_rows() {
  local rows
  grep -v '^#' "$2" >"$work/cli_rows.tum"
  rows=$(wc -l <"$work/cli_rows.tum")
  [ "$rows" -ge 20 ] || fail "voca run wrote only $rows poses into $2"
  if ! cmp -s "$work/cli_rows.tum" "$1"; then
    { diff "$work/cli_rows.tum" "$1" || true; } | head -10 >&2
    fail "the example's rows ($1) differ from voca run --out ($2)"
  fi
  echo "check_install: example: $rows rows identical to voca run --out"
}

# The same across architectures: the same frames and times, and every position and quaternion
# component within $3 of the other's. Bit-identical results need the same libm and the same
# instruction choices, which x86-64 and AArch64 builds do not share (on the KITTI 06 clip the
# arm64 poses differ by at most 2e-11 m and 3e-14 in the quaternion, from the second frame on).
compare_rows_within() {
  local rows tolerance=$3 report
  grep -v '^#' "$2" >"$work/cli_rows.tum"
  rows=$(wc -l <"$work/cli_rows.tum")
  [ "$rows" -ge 20 ] || fail "voca run wrote only $rows poses into $2"
  [ "$(wc -l <"$1")" -eq "$rows" ] || fail "the example wrote $(wc -l <"$1") rows, voca run --out $rows"
  report=$(paste -d ' ' "$work/cli_rows.tum" "$1" | awk -v tolerance="$tolerance" '
    NF != 16 || $1 != $9 { printf "row %d: frames differ: %s | %s\n", NR, $1, $9; bad = 1; exit }
    { for (i = 2; i <= 8; ++i) { d = $i - $(i + 8); if (d < 0) d = -d; if (d > worst) worst = d
        if (d > tolerance) { printf "row %d column %d: %s against %s\n", NR, i, $i, $(i + 8); bad = 1; exit } } }
    END { if (!bad) printf "%.3g", worst; exit bad }') ||
    fail "the example's rows ($1) differ from voca run --out ($2) by more than $tolerance: $report"
  if cmp -s "$work/cli_rows.tum" "$1"; then
    echo "check_install: example: $rows rows identical to voca run --out"
  else
    echo "check_install: example: $rows rows within $tolerance of voca run --out (largest difference $report)"
  fi
}

# Configures and builds examples/odometry against VocaRT found under $1 and nowhere else (no package
# registry, no system prefixes); extra arguments go to cmake (a toolchain file).
build_example() {
  local prefix=$1 found
  shift
  cmake -S examples/odometry -B "$work/example" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
    -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF \
    -DCMAKE_FIND_USE_CMAKE_SYSTEM_PATH=OFF "$@" >"$work/example-configure.log" 2>&1 ||
    { cat "$work/example-configure.log" >&2; fail "configuring examples/odometry against $prefix failed"; }
  found=$(sed -n 's/^VocaRT_DIR:PATH=//p' "$work/example/CMakeCache.txt")
  [ "$found" = "$prefix/$libdir/cmake/VocaRT" ] || fail "the example found VocaRT in '$found', not in $prefix"
  cmake --build "$work/example" >"$work/example-build.log" 2>&1 ||
    { cat "$work/example-build.log" >&2; fail "building examples/odometry against $prefix failed"; }
}

if [ "$preset" = release ]; then
  # 1. The installed tree: exactly the expected files (the Python module's folder is its own rule's).
  prefix="$work/prefix"
  quiet cmake --install build/release --prefix "$prefix"
  {
    echo bin/voca
    for h in api/include/voca_rt/*.h; do echo "include/voca_rt/${h##*/}"; done
    echo include/voca_rt/version.h
    for f in libvoca-rt.so "libvoca-rt.so.$major" "libvoca-rt.so.$version" pkgconfig/voca-rt.pc \
      cmake/VocaRT/VocaRTConfig.cmake cmake/VocaRT/VocaRTConfigVersion.cmake cmake/VocaRT/VocaRTTargets.cmake \
      cmake/VocaRT/VocaRTTargets-release.cmake; do
      echo "$libdir/$f"
    done
  } | sort >"$work/expected.txt"
  (cd "$prefix" && find . \( -type f -o -type l \) | sed 's|^\./||' | grep -v '^lib/python3/dist-packages/' | sort) \
    >"$work/installed.txt"
  if ! diff "$work/expected.txt" "$work/installed.txt" >"$work/install.diff"; then
    sed -n 's/^< /  missing: /p; s/^> /  unexpected: /p' "$work/install.diff" >&2
    fail "cmake --install installed other files than expected"
  fi
  echo "check_install: install: $(wc -l <"$work/installed.txt") files as expected"

  # 2. A CMake project against the installed tree only; it must run with the prefix's library.
  build_example "$prefix"
  # ldd's output is kept whole first: `ldd | grep -q` under pipefail fails whenever grep exits before
  # ldd has written its last line (SIGPIPE), which depends on the machine's load.
  loaded=$(ldd "$work/example/voca_example_odometry" | sed -n "s|^[[:space:]]*libvoca-rt\.so\.$major => \([^ ]*\) .*|\1|p")
  [ -n "$loaded" ] && [ "$(realpath "$loaded")" = "$(realpath "$prefix/$libdir/libvoca-rt.so.$major")" ] ||
    fail "the example loads libvoca-rt.so.$major from '${loaded:-nowhere}', not from $prefix/$libdir"

  # 3. A one-file consumer through pkg-config (only our .pc visible): the version and an exception
  # thrown inside the library caught by its type in the program.
  cat >"$work/consumer.cpp" <<'CPP'
#include <voca_rt/voca_rt.h>

#include <cstring>
#include <iostream>

int main() {
  if (std::strcmp(voca_rt::version(), VOCA_RT_VERSION) != 0) {
    std::cerr << "library " << voca_rt::version() << " != headers " << VOCA_RT_VERSION << '\n';
    return 1;
  }
  try {
    voca_rt::Calibration::load("/nonexistent/calib.json");
  } catch (const voca_rt::Error& error) {
    if (error.kind() != voca_rt::Error::Kind::kInput) return 1;
    std::cout << voca_rt::version() << '\n';
    return 0;
  }
  std::cerr << "no voca_rt::Error for a missing calibration\n";
  return 1;
}
CPP
  pc_flags=$(PKG_CONFIG_LIBDIR="$prefix/$libdir/pkgconfig" PKG_CONFIG_PATH="" pkg-config --cflags --libs voca-rt)
  # shellcheck disable=SC2086  # the flags are words
  c++ -std=c++17 -Wall -Wextra -Werror "$work/consumer.cpp" -o "$work/consumer" $pc_flags
  [ "$(LD_LIBRARY_PATH="$prefix/$libdir" "$work/consumer")" = "$version" ] || fail "the pkg-config consumer failed"
  echo "check_install: pkg-config consumer ($pc_flags) built and ran"

  # 4. Its poses against the command line's on the same video folder.
  quiet "$host_voca" encode "$data/euroc_v101_micro/mav0" --out "$work/video"
  quiet "$host_voca" run "$work/video" --out "$work/cli.tum"
  "$work/example/voca_example_odometry" "$work/video" "$work/video/calib.json" >"$work/example.tum"
  compare_rows "$work/example.tum" "$work/cli.tum"
fi

# The Debian package: its files, its Depends on the target's libraries, and the tool unpacked from it.
arch=$([ "$preset" = aarch64 ] && echo arm64 || echo amd64)
deb="build/$preset/voca-rt_${version}_${arch}.deb"
rm -f "$deb"
quiet cpack --preset "$preset"
[ -f "$deb" ] || fail "cpack did not write $deb"
dpkg-deb -c "$deb" | awk '{print $6}' | sed 's|^\./||' >"$work/deb-files.txt"
for f in usr/bin/voca usr/include/voca_rt/odometry.h usr/include/voca_rt/version.h "usr/$libdir/libvoca-rt.so" \
  "usr/$libdir/libvoca-rt.so.$major" "usr/$libdir/libvoca-rt.so.$version" "usr/$libdir/pkgconfig/voca-rt.pc" \
  "usr/$libdir/cmake/VocaRT/VocaRTConfig.cmake" "usr/$libdir/cmake/VocaRT/VocaRTTargets.cmake"; do
  grep -qx "$f" "$work/deb-files.txt" || fail "$deb lacks $f"
done
[ "$(dpkg-deb -f "$deb" Architecture)" = "$arch" ] || fail "$deb is for $(dpkg-deb -f "$deb" Architecture), not $arch"
depends=$(dpkg-deb -f "$deb" Depends)
[[ "$depends" == *libavcodec59* && "$depends" == *libc6* ]] || fail "$deb: Depends lacks the shared libraries: '$depends'"
echo "check_install: $deb ($(stat -c %s "$deb") bytes), Depends: $depends"
root="$work/root"
dpkg -x "$deb" "$root"

if [ "$preset" = release ]; then
  out=$(LD_LIBRARY_PATH="$root/usr/$libdir" "$root/usr/bin/voca" --version)
  [ "$out" = "voca $version" ] || fail "the packaged voca --version printed '$out'"
  echo "check_install: packaged voca --version: $out"
  # The Python module comes with the amd64 package, where Debian's python3 finds it, and imports.
  grep -qE '^usr/lib/python3/dist-packages/voca\..*\.so$' "$work/deb-files.txt" || fail "$deb lacks the Python module"
  py_version=$(PYTHONPATH="$root/usr/lib/python3/dist-packages" /usr/bin/python3 -c 'import voca; print(voca.__version__)')
  [ "$py_version" = "$version" ] || fail "the packaged Python module says version '$py_version'"
  echo "check_install: packaged Python module imports (voca $py_version)"
  exit 0
fi

# arm64: the example cross-built against the unpacked package, run under qemu-user as ctest runs the
# aarch64 tests (the target's libraries are installed multiarch: no -L needed then), on the KITTI 06
# clip, against the amd64 command line's rows.
build_example "$root/usr" --toolchain "$PWD/toolchains/aarch64-linux-gnu.cmake"
emulator=(qemu-aarch64-static)
[ -e /lib/ld-linux-aarch64.so.1 ] || emulator+=(-L /usr/aarch64-linux-gnu)
quiet "$host_voca" encode "$data/kitti06_first51/sequences/06" --out "$work/video"
quiet "$host_voca" run "$work/video" --config kitti --out "$work/cli.tum"
"${emulator[@]}" "$work/example/voca_example_odometry" "$work/video" "$work/video/calib.json" kitti \
  >"$work/example.tum"
# 1e-6 (a micrometre, a millionth of a quaternion component): far above what the architectures'
# rounding accumulates over the clip, far below any error of the odometry (ATE 0.13 m here).
compare_rows_within "$work/example.tum" "$work/cli.tum" 1e-6
