# Cross-build for arm64 (aarch64) with Debian's multiarch toolchain:
# crossbuild-essential-arm64 and the :arm64 -dev packages installed beside the
# build machine's own (packaging/scripts/deps_arm64.sh). Used by
# packaging/scripts/arm64.sh (docs/install.md, docs/decisions/0019).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
# Multiarch: find_library and find_package look in /usr/lib/aarch64-linux-gnu,
# never in the build machine's /usr/lib/x86_64-linux-gnu.
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
# pkgconf:arm64's wrapper reads the .pc files of the :arm64 packages.
set(PKG_CONFIG_EXECUTABLE aarch64-linux-gnu-pkg-config CACHE FILEPATH "pkg-config for arm64")
# CTest runs the tests, and gtest_discover_tests lists them, under qemu's
# user-mode emulator (Debian's qemu-user); the arm64 loader and libraries are
# the multiarch ones in /.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64)
