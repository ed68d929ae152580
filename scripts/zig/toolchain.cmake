# The CMake toolchain of `scripts/wheel --glibc X.Y` for chemfiles-sys's C++ build (the only
# CMake build in the executable). cargo-zigbuild writes one of its own, but keeps ours when
# CMAKE_TOOLCHAIN_FILE_<target> is set: ours takes the same zig wrappers from the variables
# cargo-zigbuild gives cargo (CC_/CXX_/AR_/RANLIB_<target>) and adds the project include below.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR x86_64)
set(CMAKE_C_COMPILER "$ENV{CC_x86_64_unknown_linux_gnu}")
set(CMAKE_CXX_COMPILER "$ENV{CXX_x86_64_unknown_linux_gnu}")
set(CMAKE_AR "$ENV{AR_x86_64_unknown_linux_gnu}")
set(CMAKE_RANLIB "$ENV{RANLIB_x86_64_unknown_linux_gnu}")
# zig's linker (lld) has no --dependency-file.
set(CMAKE_C_LINKER_DEPFILE_SUPPORTED FALSE)
set(CMAKE_CXX_LINKER_DEPFILE_SUPPORTED FALSE)
set(CMAKE_PROJECT_INCLUDE "${CMAKE_CURRENT_LIST_DIR}/cxx-runtime.cmake")
