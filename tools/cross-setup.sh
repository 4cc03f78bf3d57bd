#!/usr/bin/env bash
# Prepares a Debian 12 amd64 machine to cross-build VOCA-RT for ARM and run its unit tests under
# qemu-user: Debian's cross compiler, qemu-user-static, and the ARM builds of our -dev packages
# installed beside the amd64 ones (multiarch). Idempotent: when everything is present it only
# checks and returns. Run as root, or as a user with sudo.
#
#   bash tools/cross-setup.sh [aarch64|armhf]      (default aarch64)
#
# It refuses to go on if apt would remove any installed package: the ARM -dev packages must
# co-install with the native ones (Multi-Arch: same), they must never replace them.
set -euo pipefail

target="${1:-aarch64}"
case "$target" in
  aarch64) arch=arm64 triplet=aarch64-linux-gnu ;;
  armhf) arch=armhf triplet=arm-linux-gnueabihf ;;
  *) echo "cross-setup: unknown target '$target' (expected aarch64 or armhf)" >&2; exit 1 ;;
esac

# The ARM counterparts of the compiled -dev packages in tools/setup.sh. Header-only and arch:all
# packages (Eigen, nlohmann-json, CLI11, doctest, the queues) serve every architecture as they are.
# libva/libdrm/libcamera feed optional drivers; they are installed so CI cross-builds those too.
# cyclonedds-dev is Multi-Arch: same; its code generator idlc (cyclonedds-tools) runs on the build
# machine, so only the amd64 one is needed.
dev_packages=(
  libavcodec-dev libavformat-dev libavutil-dev libswscale-dev libx264-dev
  libva-dev libdrm-dev libcamera-dev
  libfmt-dev libpng-dev
  cyclonedds-dev
)
# Debian 12's libyaml-cpp-dev is not Multi-Arch: same, so its ARM build cannot be installed beside
# the amd64 one. We install the ARM runtime library with apt and unpack the ARM -dev package (CMake
# config, headers, .so link) into a private overlay that the toolchain file searches first.
overlay_dev=libyaml-cpp-dev
overlay_runtime=libyaml-cpp0.7
overlay_root="${VOCA_CROSS_OVERLAY:-/opt/voca-cross}/$triplet"

packages=("g++-$triplet" qemu-user-static "$overlay_runtime:$arch")
for p in "${dev_packages[@]}"; do packages+=("$p:$arch"); done

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

sudo=""
as_root() {
  if [ "$(id -u)" -ne 0 ] && [ -z "$sudo" ]; then
    command -v sudo >/dev/null || { echo "cross-setup: need root (or sudo) for: $*" >&2; exit 1; }
    sudo="sudo"
  fi
  $sudo "$@"
}

missing=()
for p in "${packages[@]}"; do installed "$p" || missing+=("$p"); done
runtime_version=$(dpkg-query -W -f='${Version}' "$overlay_runtime:$arch" 2>/dev/null || true)
overlay_ok=0
if [ -n "$runtime_version" ] && [ "$(cat "$overlay_root/.voca-overlay" 2>/dev/null)" = "$overlay_dev $runtime_version" ]; then
  overlay_ok=1
fi

if [ ${#missing[@]} -eq 0 ] && [ $overlay_ok -eq 1 ]; then
  echo "cross-setup: $target: all ${#packages[@]} packages and the $overlay_dev overlay present"
  exit 0
fi

export DEBIAN_FRONTEND=noninteractive
if [ ${#missing[@]} -gt 0 ]; then
  added_arch=0
  if ! dpkg --print-foreign-architectures | grep -qx "$arch"; then
    echo "cross-setup: adding dpkg architecture $arch"
    as_root dpkg --add-architecture "$arch"
    added_arch=1
  fi
  # Prints the reason and stops. An architecture this run added is taken away again while nothing
  # of it is installed: left behind with a broken index, it would fail every later `apt-get update`
  # on the machine (tools/setup.sh's too), not just ours.
  give_up() {
    printf 'cross-setup: %s\n' "$@" >&2
    if [ $added_arch -eq 1 ] && as_root dpkg --remove-architecture "$arch" 2>/dev/null; then
      echo "cross-setup: removed dpkg architecture $arch again; nothing was installed" >&2
    fi
    exit 1
  }
  # A mirror caught mid-sync fails the update for one index ("File has unexpected size") and
  # usually passes a bit later. If it keeps failing, go on with the lists apt has: when what we
  # need is in them the install works; when not, the dry run below fails and names the index.
  update_errors=""
  for try in 1 2 3; do
    if update_errors=$(as_root apt-get update -qq 2>&1); then
      update_errors=""
      break
    fi
    printf '%s\n' "$update_errors" >&2
    if [ "$try" -lt 3 ]; then
      echo "cross-setup: apt-get update failed, retrying in 20 s" >&2
      sleep 20
    else
      echo "cross-setup: apt-get update failed 3 times; using the package lists apt already has" >&2
    fi
  done
  # Dry run first: a version skew between the native and ARM -dev packages, or a package that is
  # not Multi-Arch: same, shows up as a removal. Upgrades of native packages to the ARM ones'
  # version are expected (Multi-Arch: same needs identical versions) and are allowed.
  if ! plan=$(as_root apt-get install -s --no-install-recommends "${missing[@]}" 2>&1); then
    printf '%s\n' "$plan" | grep -E '^ |^E:' >&2 || true
    broken=$(printf '%s\n' "$update_errors" | sed -n 's/^E: Failed to fetch \([^ ]*\) *\(.*\)$/  \1 (\2)/p')
    if [ -n "$broken" ]; then
      give_up "apt cannot install the $arch packages because it could not fetch this package index:" \
        "$broken" \
        "Without that index apt lacks the $arch builds of versions installed here for amd64, and" \
        "multiarch (Multi-Arch: same) packages must be at identical versions for both. A size or hash" \
        "mismatch means the mirror serves a stale or half-synced file: run this script again later."
    fi
    give_up "apt cannot install ${missing[*]} (its reasons above)"
  fi
  removals=$(printf '%s\n' "$plan" | sed -n 's/^Remv \([^ ]*\).*/\1/p')
  if [ -n "$removals" ]; then
    give_up "installing ${missing[*]} would remove: $(echo $removals)" \
      "refusing; install the native packages at the same version first (tools/setup.sh)"
  fi
  echo "cross-setup: installing ${missing[*]}"
  as_root apt-get install -y -qq --no-install-recommends "${missing[@]}"
  runtime_version=$(dpkg-query -W -f='${Version}' "$overlay_runtime:$arch")
fi

if [ "$(cat "$overlay_root/.voca-overlay" 2>/dev/null)" != "$overlay_dev $runtime_version" ]; then
  echo "cross-setup: unpacking $overlay_dev:$arch $runtime_version into $overlay_root"
  work=$(mktemp -d)
  chmod 777 "$work"  # apt fetches as its own unprivileged user (_apt)
  trap 'rm -rf "$work"' EXIT
  # apt-get download runs as the calling user and writes to the current directory.
  (cd "$work" && apt-get download -qq "$overlay_dev:$arch=$runtime_version")
  as_root rm -rf "$overlay_root"
  as_root mkdir -p "$overlay_root"
  as_root dpkg-deb -x "$work"/*.deb "$overlay_root"
  # The -dev package's .so link and CMake config name the runtime library beside them; point those
  # names at the runtime package's files in the multiarch directory.
  for f in $(dpkg-query -L "$overlay_runtime:$arch" | grep "^/usr/lib/$triplet/[^/]*\.so"); do
    as_root ln -sfn "$f" "$overlay_root$f"
  done
  echo "$overlay_dev $runtime_version" | as_root tee "$overlay_root/.voca-overlay" >/dev/null
fi
echo "cross-setup: $target: done"
