# Shared part of the Debian cross toolchain files: the caller sets CMAKE_SYSTEM_PROCESSOR,
# VOCA_CROSS_TRIPLET (GNU triplet, also the multiarch directory name) and VOCA_CROSS_QEMU (qemu-user
# name of the CPU). Libraries come from the multiarch directories that tools/cross-setup.sh fills
# (/usr/lib/<triplet>, /usr/include/<triplet>); headers-only and arch:all packages are shared with
# the host. Test executables run under qemu-user, so `ctest` works on the build machine.
set(CMAKE_SYSTEM_NAME Linux)

set(CMAKE_C_COMPILER ${VOCA_CROSS_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${VOCA_CROSS_TRIPLET}-g++)
# CMake derives this from the compiler too; stating it keeps find_library/find_package away from
# the host's /usr/lib/x86_64-linux-gnu even if the detection changes.
set(CMAKE_LIBRARY_ARCHITECTURE ${VOCA_CROSS_TRIPLET})

# Packages that Debian does not ship Multi-Arch: same (yaml-cpp) are unpacked by cross-setup.sh into
# a private overlay; it is searched before the system root.
if(DEFINED ENV{VOCA_CROSS_OVERLAY})
  set(VOCA_CROSS_OVERLAY "$ENV{VOCA_CROSS_OVERLAY}/${VOCA_CROSS_TRIPLET}")
else()
  set(VOCA_CROSS_OVERLAY "/opt/voca-cross/${VOCA_CROSS_TRIPLET}")
endif()
set(CMAKE_FIND_ROOT_PATH ${VOCA_CROSS_OVERLAY} /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)  # build tools (pkg-config, ...) run on the host
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config must see only the target's .pc files (and arch-independent ones), never the host's.
# The toolchain file is read on every configure, so this holds for re-configures during a build.
set(ENV{PKG_CONFIG_LIBDIR}
    "${VOCA_CROSS_OVERLAY}/usr/lib/${VOCA_CROSS_TRIPLET}/pkgconfig:/usr/lib/${VOCA_CROSS_TRIPLET}/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")
unset(ENV{PKG_CONFIG_SYSROOT_DIR})

# Run test executables (add_test with a target as COMMAND) through qemu-user. -L makes qemu find
# the target's dynamic loader and libc in the cross toolchain's directory; the other libraries
# resolve in the multiarch directories as on a Debian board.
find_program(VOCA_QEMU NAMES qemu-${VOCA_CROSS_QEMU}-static qemu-${VOCA_CROSS_QEMU} NO_CMAKE_FIND_ROOT_PATH)
if(VOCA_QEMU)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${VOCA_QEMU} -L /usr/${VOCA_CROSS_TRIPLET})
else()
  message(WARNING "qemu-${VOCA_CROSS_QEMU}-static not found (bash tools/cross-setup.sh installs it): "
                  "the build works, but ctest cannot run the ${CMAKE_SYSTEM_PROCESSOR} test executables here")
endif()
