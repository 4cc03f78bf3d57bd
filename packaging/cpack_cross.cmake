# Read by cpack for a cross build (CPACK_PROJECT_CONFIG_FILE). dpkg-shlibdeps takes the target's
# architecture from DEB_HOST_ARCH: it then reads the binaries with the target's objdump
# (aarch64-linux-gnu-objdump) and searches the target's multiarch folders (/usr/lib/<triplet>, where
# tools/cross-setup.sh installs the :arm64 libraries) rather than relying on the build machine's
# objdump and ld.so.conf to cover a foreign architecture.
set(ENV{DEB_HOST_ARCH} "${CPACK_DEBIAN_PACKAGE_ARCHITECTURE}")
