#!/usr/bin/env bash
# Builds the third-party libraries libdqjulia links statically, from Debian 12's own source
# packages (the same versions Debian ships as shared libraries), as static, position-independent
# archives in a cache outside the checkout:
#
#   zlib 1.2.13, libpng 1.6.39, Imath 3.1.6, OpenEXR 3.1.5, oneTBB 2021.8.0,
#   Highway 1.0.3, OpenVDB 10.0.1 (no Blosc, no delayed loading: no Boost libraries)
#
# Usage: scripts/build-deps.sh            builds what is missing, then prints the prefix
#        scripts/build-deps.sh --print    prints the prefix only (CMake reads it)
#
# The prefix is $DQJ_DEPS_CACHE/linux-x64-<key>, where DQJ_DEPS_CACHE defaults to
# ${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/deps and <key> names the versions and the recipe
# revision, so a change of either builds anew beside the old one. A finished prefix is
# complete (it is built in a temporary folder and renamed into place); a second run costs
# nothing. About 8 minutes on 2 cores the first time. Needs: build-essential, cmake,
# libboost-dev (headers only), and network access to Debian's archive (deb-src).
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
versions="zlib-1.2.13_png-1.6.39_imath-3.1.6_exr-3.1.5_tbb-2021.8.0_hwy-1.0.3_vdb-10.0.1"
recipe=1  # bump when the build options below change
key="${versions}_r${recipe}"
cache="${DQJ_DEPS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/deps}"
prefix="$cache/linux-x64-$key"

if [ "${1:-}" = "--print" ]; then
  echo "$prefix"
  exit 0
fi
if [ -f "$prefix/.complete" ]; then
  echo "$prefix"
  exit 0
fi

# Debian's CMake 3.25: the pip one (4.x) refuses these projects' old cmake_minimum_required.
cmake_bin=/usr/bin/cmake
[ -x "$cmake_bin" ] || cmake_bin=cmake
jobs=$(nproc)
mkdir -p "$cache"
work=$(mktemp -d "$cache/.build-XXXXXX")
trap 'rm -rf "$work"' EXIT
stage="$work/prefix"
start=$(date +%s)
log() { echo "dqjulia deps: $* ($(($(date +%s) - start)) s)" >&2; }

# --- sources: Debian's source packages, through a private apt state (the system's is untouched).
apt_dir="$work/apt"
mkdir -p "$apt_dir/parts" "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial" "$work/src"
sources=/etc/apt/sources.list.d/debian.sources
[ -f "$sources" ] && sed 's/^Types:.*/Types: deb-src/' "$sources" > "$apt_dir/parts/debian.sources"
if [ ! -s "$apt_dir/parts/debian.sources" ]; then
  echo "dqjulia deps: no Debian apt sources found (/etc/apt/sources.list.d/debian.sources)" >&2
  exit 1
fi
apt_opts=(-o Dir::Etc::sourcelist=/dev/null -o "Dir::Etc::sourceparts=$apt_dir/parts"
          -o "Dir::State::Lists=$apt_dir/lists" -o "Dir::Cache=$apt_dir/cache" -o APT::Sandbox::User=root)
apt-get "${apt_opts[@]}" -q update >/dev/null
# Only the upstream tarball (.orig) is needed; apt checks its hash against Debian's index.
# Some Debian parts (.debian.tar.xz, a security update's .dsc) may be missing from the mirror.
fetch() {  # fetch PACKAGE=VERSION ORIG_GLOB
  (cd "$work/src" && apt-get "${apt_opts[@]}" -q source --download-only "$1" >/dev/null 2>&1) || true
  local orig
  orig=$(ls "$work/src"/$2 2>/dev/null | head -n 1)
  if [ -z "$orig" ]; then
    echo "dqjulia deps: could not download the Debian source of $1 ($2)" >&2
    exit 1
  fi
  mkdir -p "$work/src/${1%%=*}"
  tar -xf "$orig" -C "$work/src/${1%%=*}" --strip-components=1
}
fetch zlib 'zlib_1.2.13*.orig.tar.*'
fetch libpng1.6 'libpng1.6_1.6.39.orig.tar.*'
fetch imath 'imath_3.1.6.orig.tar.*'
fetch openexr 'openexr_3.1.5.orig.tar.*'
fetch onetbb 'onetbb_2021.8.0.orig.tar.*'
fetch highway 'highway_1.0.3.orig.tar.*'
fetch openvdb 'openvdb_10.0.1.orig.tar.*'
log "sources fetched"

common=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_POSITION_INDEPENDENT_CODE=ON -DBUILD_SHARED_LIBS=OFF
        "-DCMAKE_INSTALL_PREFIX=$stage" "-DCMAKE_PREFIX_PATH=$stage" -DCMAKE_INSTALL_LIBDIR=lib
        -DCMAKE_POLICY_VERSION_MINIMUM=3.5)
build() {  # build NAME [CMAKE OPTIONS...]
  local name=$1
  shift
  "$cmake_bin" -S "$work/src/$name" -B "$work/build/$name" "${common[@]}" "$@" >"$work/$name.log" 2>&1 \
    && "$cmake_bin" --build "$work/build/$name" -j"$jobs" >>"$work/$name.log" 2>&1 \
    && "$cmake_bin" --install "$work/build/$name" >>"$work/$name.log" 2>&1 \
    || { tail -n 40 "$work/$name.log" >&2; echo "dqjulia deps: building $name failed" >&2; exit 1; }
  log "built $name"
}

# zlib: its own configure makes only the static archive.
(cd "$work/src/zlib" && CFLAGS="-O2 -fPIC" ./configure --static --prefix="$stage" >"$work/zlib.log" 2>&1 \
  && make -j"$jobs" libz.a >>"$work/zlib.log" 2>&1 && make install >>"$work/zlib.log" 2>&1) \
  || { tail -n 40 "$work/zlib.log" >&2; echo "dqjulia deps: building zlib failed" >&2; exit 1; }
log "built zlib"
zlib_opts=("-DZLIB_ROOT=$stage" "-DZLIB_LIBRARY=$stage/lib/libz.a" "-DZLIB_INCLUDE_DIR=$stage/include")

build libpng1.6 "${zlib_opts[@]}" -DPNG_SHARED=OFF -DPNG_STATIC=ON -DPNG_TESTS=OFF -DPNG_EXECUTABLES=OFF
build imath -DBUILD_TESTING=OFF -DPYTHON=OFF
build openexr "${zlib_opts[@]}" -DBUILD_TESTING=OFF -DOPENEXR_BUILD_TOOLS=OFF -DOPENEXR_INSTALL_EXAMPLES=OFF \
  -DOPENEXR_INSTALL_TOOLS=OFF -DOPENEXR_INSTALL_PKG_CONFIG=OFF
build onetbb -DTBB_TEST=OFF -DTBB_STRICT=OFF -DTBB_EXAMPLES=OFF -DTBBMALLOC_BUILD=OFF
build highway -DHWY_ENABLE_TESTS=OFF -DHWY_ENABLE_EXAMPLES=OFF -DHWY_ENABLE_CONTRIB=OFF -DHWY_ENABLE_INSTALL=ON \
  -DHWY_FORCE_STATIC_LIBS=ON -DBUILD_TESTING=OFF
build openvdb "${zlib_opts[@]}" "-DTBB_ROOT=$stage" -DOPENVDB_CORE_SHARED=OFF -DOPENVDB_CORE_STATIC=ON \
  -DOPENVDB_BUILD_BINARIES=OFF -DOPENVDB_BUILD_PYTHON_MODULE=OFF -DOPENVDB_BUILD_UNITTESTS=OFF \
  -DOPENVDB_BUILD_DOCS=OFF -DUSE_BLOSC=OFF -DUSE_ZLIB=ON -DUSE_EXPLICIT_INSTANTIATION=OFF \
  -DOPENVDB_USE_DELAYED_LOADING=OFF -DUSE_PKGCONFIG=OFF

echo "$versions" > "$stage/.complete"
rm -rf "$prefix"
mv "$stage" "$prefix"
log "done: $prefix"
echo "$prefix"
