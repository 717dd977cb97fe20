#!/usr/bin/env bash
# Build organtex's C API in release and install it under a prefix:
#   lib/liborgantex.so.VERSION (+ .so.ABI and .so links), lib/liborgantex.a,
#   include/organtex.h, include/organtex.hpp,
#   lib/pkgconfig/organtex.pc, lib/cmake/organtex/organtexConfig*.cmake.
#
#   capi/install.sh [--prefix DIR]     (default /usr/local)
#
# Then: pkg-config --cflags --libs organtex, or find_package(organtex) and
# target_link_libraries(app organtex::organtex) in CMake.
set -euo pipefail
prefix=/usr/local
while [ $# -gt 0 ]; do
    case "$1" in
        --prefix) prefix="$2"; shift 2 ;;
        --prefix=*) prefix="${1#--prefix=}"; shift ;;
        -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
        *) echo "install.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
    esac
done
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here/.."
cargo build --release -p organtex-capi
target="${CARGO_TARGET_DIR:-$PWD/target}/release"
version="$(sed -n 's/^version = "\(.*\)"/\1/p' capi/Cargo.toml | head -1)"
abi="$(sed -n 's/^pub const ORGANTEX_ABI_VERSION: u32 = \([0-9]*\);/\1/p' capi/src/lib.rs)"
major="${version%%.*}"; rest="${version#*.}"; minor="${rest%%.*}"
# What liborgantex.a needs from the system (cargo --print native-static-libs).
static_libs="gcc_s;util;rt;pthread;m;dl;c"
static_flags="-lgcc_s -lutil -lrt -lpthread -lm -ldl -lc"

mkdir -p "$prefix/lib/pkgconfig" "$prefix/lib/cmake/organtex" "$prefix/include"
# Debug line tables stay out of the installed library (they are 9/10 of it).
strip --strip-debug -o "$prefix/lib/liborgantex.so.$version" "$target/liborgantex_capi.so"
ln -sf "liborgantex.so.$version" "$prefix/lib/liborgantex.so.$abi"
ln -sf "liborgantex.so.$abi" "$prefix/lib/liborgantex.so"
strip --strip-debug -o "$prefix/lib/liborgantex.a" "$target/liborgantex_capi.a"
install -m 644 capi/include/organtex.h capi/include/organtex.hpp "$prefix/include/"
subst() {
    sed -e "s|@VERSION@|$version|g" -e "s|@ABI@|$abi|g" -e "s|@MAJOR@|$major|g" \
        -e "s|@MINOR@|$minor|g" -e "s|@PREFIX@|$prefix|g" -e "s|@STATIC_LIBS@|$static_libs|g" \
        -e "s|@STATIC_LIBS_FLAGS@|$static_flags|g" "$1" > "$2"
}
subst capi/cmake/organtex.pc.in "$prefix/lib/pkgconfig/organtex.pc"
subst capi/cmake/organtexConfig.cmake.in "$prefix/lib/cmake/organtex/organtexConfig.cmake"
subst capi/cmake/organtexConfigVersion.cmake.in "$prefix/lib/cmake/organtex/organtexConfigVersion.cmake"
echo "installed organtex $version (ABI $abi) under $prefix"
