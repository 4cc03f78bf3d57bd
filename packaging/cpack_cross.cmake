# Read by cpack for a cross build (CPACK_PROJECT_CONFIG_FILE). dpkg-shlibdeps takes the architecture
# whose multiarch folders (/usr/lib/<triplet>) and package databases it searches from DEB_HOST_ARCH;
# without it, it looks for the target's libraries among the build machine's and finds none.
set(ENV{DEB_HOST_ARCH} "${CPACK_DEBIAN_PACKAGE_ARCHITECTURE}")
