# Cross build for the small Linux computer beside the sbRIO: 32-bit ARM, armv7-a, hard float
# (Debian's armhf), with Debian's cross compiler (g++-arm-linux-gnueabihf). Programs are linked
# statically (-static: no dependency on the target's C library); libsodium comes from Debian's
# armhf package (libsodium-dev:armhf, its static archive). Header-only dependencies (Eigen, Boost,
# CLI11, nlohmann-json, fmt in header-only mode) are the host's: they are the same for every
# architecture. `./run cross` uses this file; programs run on the host under qemu-arm-static.
#   cmake -S . -B build-armhf -DCMAKE_TOOLCHAIN_FILE=cmake/armhf-toolchain.cmake
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-linux-gnueabihf-gcc)
set(CMAKE_CXX_COMPILER arm-linux-gnueabihf-g++)
set(CMAKE_LIBRARY_ARCHITECTURE arm-linux-gnueabihf)
set(CMAKE_C_FLAGS_INIT "-march=armv7-a -mfpu=vfpv3-d16 -mfloat-abi=hard")
set(CMAKE_CXX_FLAGS_INIT "-march=armv7-a -mfpu=vfpv3-d16 -mfloat-abi=hard")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-static")
# libsodium's static archive: pkg-config's IMPORTED_TARGET would take the shared library (CMake's
# Linux platform file puts .so first, whatever a toolchain file sets).
set(pkgcfg_lib_SODIUM_sodium "/usr/lib/arm-linux-gnueabihf/libsodium.a" CACHE FILEPATH
  "libsodium for the armhf static link" FORCE)
set(CMAKE_FIND_ROOT_PATH /usr/arm-linux-gnueabihf)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
# pkg-config (libsodium) reads the armhf package's .pc file only.
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/arm-linux-gnueabihf/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")
# Boost is used header-only: the host's package configuration names the same headers.
file(GLOB _eh_boost_dir "/usr/lib/x86_64-linux-gnu/cmake/Boost-*")
if(_eh_boost_dir AND NOT Boost_DIR)
  list(GET _eh_boost_dir 0 _eh_boost_dir)
  set(Boost_DIR "${_eh_boost_dir}" CACHE PATH "Boost's CMake package (headers only)")
endif()
# CTest and add_custom_command run armhf programs through qemu.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm-static)
