# The Debian package voca-rt: libvoca-rt.so, its headers, CMake package and voca-rt.pc, and the voca
# tool, with Depends computed by dpkg-shlibdeps from what the binaries link. After building voca and
# voca_rt: `cpack --preset release` (amd64) or `cpack --preset aarch64` (arm64, cross build), giving
# build/<preset>/voca-rt_<version>_<arch>.deb.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME voca-rt)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "VOCA-RT maintainers <maintainers@users.noreply.h-seed-db25161e.example>"
    CACHE STRING "Maintainer of the Debian package (Name <email>)")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "causal stereo visual odometry on H.264 video")
string(JOIN " " CPACK_PACKAGE_DESCRIPTION
    "VOCA-RT estimates a 6-DoF pose for every stereo frame as soon as it arrives, using the motion vectors"
    "of the H.264 decoder as priors for KLT tracking. The package holds the shared library libvoca-rt.so"
    "with its C++ headers, CMake package (find_package(VocaRT)) and pkg-config file (voca-rt), and the"
    "voca command line.")
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # voca-rt_<version>_<arch>.deb
set(CPACK_PACKAGE_DIRECTORY ${PROJECT_BINARY_DIR})
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)  # programs packaged against libvoca-rt.so.0 get a Depends on us
# Install with DESTDIR into the staging folder, so the install step sees the package's own prefix
# (/usr), which voca-rt.pc names.
set(CPACK_SET_DESTDIR ON)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)

# A cross build is packaged for its target: the package's architecture, and dpkg-shlibdeps looking up
# the target's libraries (installed multiarch by tools/cross-setup.sh) instead of the host's.
if(CMAKE_CROSSCOMPILING)
  if(CMAKE_SYSTEM_PROCESSOR STREQUAL "aarch64")
    set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE arm64)
  elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^arm")
    set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE armhf)
  else()
    message(FATAL_ERROR "packaging/debian.cmake: no Debian architecture known for ${CMAKE_SYSTEM_PROCESSOR}")
  endif()
  set(CPACK_PROJECT_CONFIG_FILE ${PROJECT_SOURCE_DIR}/packaging/cpack_cross.cmake)
endif()

include(CPack)
