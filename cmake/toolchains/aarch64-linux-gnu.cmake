# Cross build for Debian 12 arm64 (Raspberry Pi 4/5, Jetson, Odroid) from an
# amd64 machine: Debian's aarch64-linux-gnu cross compiler (package
# crossbuild-essential-arm64) against a sysroot unpacked from Debian's arm64
# packages by scripts/arm64-sysroot. scripts/build-arm64 passes the sysroot as
# CEILPOSE_ARM64_SYSROOT; tests run under qemu-aarch64 user emulation.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

# try_compile projects re-read this file without the cache.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES CEILPOSE_ARM64_SYSROOT)
if(NOT CEILPOSE_ARM64_SYSROOT)
  message(FATAL_ERROR "CEILPOSE_ARM64_SYSROOT is not set: give the arm64 sysroot that "
                      "scripts/arm64-sysroot made (scripts/build-arm64 does)")
endif()
set(CMAKE_SYSROOT "${CEILPOSE_ARM64_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH "${CEILPOSE_ARM64_SYSROOT}")
# Programs (idlc, python3 for generators) are the build machine's;
# libraries, headers and CMake packages only the sysroot's.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

set(ENV{PKG_CONFIG_SYSROOT_DIR} "${CEILPOSE_ARM64_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${CEILPOSE_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${CEILPOSE_ARM64_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# Test executables (and gtest_discover_tests) run under user emulation, with
# the sysroot's loader and libraries.
find_program(CEILPOSE_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64 REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR "${CEILPOSE_QEMU_AARCH64};-L;${CEILPOSE_ARM64_SYSROOT}")
