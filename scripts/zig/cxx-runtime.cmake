# Included by CMake at the end of chemfiles-sys's project() (CMAKE_PROJECT_INCLUDE, set in
# toolchain.cmake), before its CMakeLists.txt lists the C++ runtime for the Rust link.
#
# chemfiles-sys's build script turns each of CMAKE_CXX_IMPLICIT_LINK_LIBRARIES into a
# `cargo:rustc-link-lib=`. With zig as the compiler these are absolute paths of the static
# archives in zig's cache (libc++.a, libc++abi.a, libunwind.a, libcompiler_rt.a, libubsan_rt.a,
# libc_nonshared.a), and the link fails: "cannot use absolute path as a system library". zig
# links its own static libc++ (with libc++abi) for `-lc++`, and the rest by itself.
set(CMAKE_CXX_IMPLICIT_LINK_LIBRARIES c++)
set(CMAKE_CXX_IMPLICIT_LINK_DIRECTORIES "")
