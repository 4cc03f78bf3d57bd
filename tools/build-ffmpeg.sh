#!/usr/bin/env bash
# Builds Debian 12's own FFmpeg release (apt-get source ffmpeg) with --enable-gray, so that the
# software decoder can skip the chroma planes VOCA never reads (DecoderOptions::luma_only): about a
# tenth less decode time, the same luma planes (`voca bench decode` checks both). Debian's package is
# built without it. Installs shared libraries into PREFIX (default: build/ffmpeg-gray) and prints the
# configure command that builds VOCA-RT against them.
#
#   bash tools/build-ffmpeg.sh [PREFIX]
#
# Needs Debian's deb-src archive (read from the same mirror as the binary packages), nasm and the
# libraries VOCA's features use: libx264 (encoding), libva (VAAPI), the kernel's V4L2 headers.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
prefix="$(realpath -m "${1:-$root/build/ffmpeg-gray}")"
work="$root/build/ffmpeg-src"
jobs="$(nproc)"

sudo_cmd=()
[[ $(id -u) -eq 0 ]] || sudo_cmd=(sudo)
"${sudo_cmd[@]}" apt-get install -y --no-install-recommends nasm pkg-config libx264-dev libva-dev dpkg-dev xz-utils >/dev/null

mkdir -p "$work/lists/partial"
cd "$work"
# A deb-src list of its own, beside the system's: nothing in /etc/apt changes.
mirror="$(sed -n 's/^URIs: *//p' /etc/apt/sources.list.d/debian.sources 2>/dev/null | head -n1)"
mirror="${mirror:-http://deb.debian.org/debian}"
cat >"$work/sources.list" <<EOF
deb-src $mirror bookworm main
deb-src $mirror bookworm-updates main
EOF
apt_opts=(-o Dir::Etc::sourcelist="$work/sources.list" -o Dir::Etc::sourceparts=- -o Dir::State::Lists="$work/lists")
"${sudo_cmd[@]}" apt-get "${apt_opts[@]}" update >/dev/null
if ! ls ffmpeg_*.orig.tar.xz >/dev/null 2>&1; then
  "${sudo_cmd[@]}" apt-get "${apt_opts[@]}" source --download-only ffmpeg >"$work/source.log" 2>&1 ||
    { tail -n 5 "$work/source.log"; echo "cannot download FFmpeg's source (deb-src from $mirror)" >&2; exit 1; }
fi
tarball="$(ls ffmpeg_*.orig.tar.xz | sort -V | tail -n1)"
version="${tarball#ffmpeg_}"
version="${version%.orig.tar.xz}"
src="$work/ffmpeg-$version"
[[ -d "$src" ]] || tar xf "$tarball"

cd "$src"
echo "FFmpeg $version -> $prefix (with --enable-gray; $jobs jobs, about 4 minutes on 2 cores)"
./configure --prefix="$prefix" --enable-gpl --enable-libx264 --enable-gray --enable-shared --disable-static \
  --disable-programs --disable-doc --enable-vaapi --enable-v4l2-m2m >"$work/configure.log" 2>&1 ||
  { tail -n 20 "$work/configure.log"; exit 1; }
make -j"$jobs" >"$work/make.log" 2>&1 || { tail -n 30 "$work/make.log"; exit 1; }
make install >/dev/null

echo "done. Build VOCA-RT against it:"
echo "  PKG_CONFIG_PATH=$prefix/lib/pkgconfig cmake --preset release -B build/release-gray -DCMAKE_BUILD_RPATH=$prefix/lib"
echo "  cmake --build build/release-gray && build/release-gray/bin/voca bench decode"
