#!/usr/bin/env bash
# Builds the third-party libraries libdqjulia links statically, from Debian 12's own source
# packages (the same versions Debian ships as shared libraries), as static archives in a cache
# outside the checkout:
#
#   zlib 1.2.13, libpng 1.6.39, Imath 3.1.6, OpenEXR 3.1.5, oneTBB 2021.8.0,
#   Highway 1.0.3, LZ4 1.9.4, c-blosc 1.21.3, OpenVDB 10.0.1 (with Blosc; no delayed loading:
#   no Boost libraries; scripts/patches/ makes its readers safe for damaged files: bounds
#   checks in its chunk readers, bools read from a file made valid, node origins checked,
#   nothing leaked when a read fails)
#
# Debian's c-blosc source ("1.21.3+ds") has its bundled codecs stripped: it is built against
# our LZ4 (Debian's lz4 source; the codec OpenVDB's Blosc compression uses) and zlib, without
# Zstd and Snappy, which OpenVDB never writes (Debian's libblosc1 links all four).
#
# for Linux x86-64 (position-independent), or for Windows x64 with MinGW-w64
# (cmake/toolchains/mingw-w64-x86_64.cmake). FreeType 2.12.1 (the command's contact sheets) is
# built for both, so the command depends on nothing but glibc or Windows' own DLLs too. For
# Windows the command's and the tests' other libraries come from Debian's sources as well, since
# the build machine's own are Linux ones: GoogleTest 1.12.1, and the header-only GLM 0.9.9.8,
# nlohmann/json 3.11.2 and CLI11 2.1.2 (the Linux build takes Debian's packages of the same
# versions; their sources are fetched there too, for their licences). Boost stays header-only:
# the Windows prefix links to the system's Boost headers (libboost-dev) in include/boost, which
# OpenVDB's headers include.
#
# Licences: each component's licence and notice files, from its Debian source, go to
# share/licenses/<Debian source package>/ in the prefix, with a SOURCE file naming the Debian
# source and its upstream tarball's SHA-256; the toolchain's runtime libraries linked in
# (libstdc++ and libgcc, MinGW-w64's runtime and winpthreads) and Boost's headers bring their
# Debian packages' copyright files. The build assembles its notices from these
# (scripts/notices.py, third_party/components.json); tests/release checks that both agree.
# Paths of the temporary build folder are mapped away (-ffile-prefix-map), so the archives hold
# none of them.
#
# Usage: scripts/build-deps.sh [--target linux-x64|windows-x64]           builds what is missing,
#                                                                          then prints the prefix
#        scripts/build-deps.sh [--target linux-x64|windows-x64] --print   prints the prefix only
#
# The prefix is $DQJ_DEPS_CACHE/<target>-<key>, where DQJ_DEPS_CACHE defaults to
# ${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/deps and <key> names the versions and the recipe
# revision, so a change of either builds anew beside the old one. A finished prefix is
# complete (it is built in a temporary folder and renamed into place); a second run costs
# nothing. About 8 minutes on 2 cores the first time (Windows: about 6). Needs: build-essential,
# cmake, libboost-dev (headers only), for Windows g++-mingw-w64-x86-64-posix, and network access
# to Debian's archive (deb-src).
set -euo pipefail

target=linux-x64
print=0
while [ $# -gt 0 ]; do
  case "$1" in
    --print) print=1 ;;
    --target) target=${2:-}; shift ;;
    --target=*) target=${1#--target=} ;;
    *) echo "usage: scripts/build-deps.sh [--target linux-x64|windows-x64] [--print]" >&2; exit 2 ;;
  esac
  shift
done

here=$(cd "$(dirname "$0")" && pwd)
versions="zlib-1.2.13_png-1.6.39_imath-3.1.6_exr-3.1.5_tbb-2021.8.0_hwy-1.0.3_lz4-1.9.4_blosc-1.21.3_vdb-10.0.1"
versions="${versions}_ft-2.12.1_glm-0.9.9.8_json-3.11.2_cli11-2.1.2"
case "$target" in
  linux-x64) recipe=9 ;;  # bump when the build options, patches or licence files below change
  windows-x64)
    versions="${versions}_gtest-1.12.1"
    recipe=12 ;;
  *) echo "dqjulia deps: unknown target '$target' (linux-x64 or windows-x64)" >&2; exit 2 ;;
esac
key="${versions}_r${recipe}"
cache="${DQJ_DEPS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/deps}"
prefix="$cache/$target-$key"

if [ "$print" = 1 ]; then
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
mingw=x86_64-w64-mingw32
if [ "$target" = windows-x64 ] && ! command -v $mingw-g++-posix >/dev/null; then
  echo "dqjulia deps: $mingw-g++-posix is missing: install g++-mingw-w64-x86-64-posix (scripts/install-deps.sh)" >&2
  exit 1
fi
jobs=$(nproc)
mkdir -p "$cache"
work=$(mktemp -d "$cache/.build-XXXXXX")
trap 'rm -rf "$work"' EXIT
stage="$work/prefix"
start=$(date +%s)
log() { echo "dqjulia deps ($target): $* ($(($(date +%s) - start)) s)" >&2; }

# --- sources: Debian's source packages, through a private apt state (the system's is untouched).
apt_dir="$work/apt"
mkdir -p "$apt_dir/parts" "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial" "$work/src"
sources=/etc/apt/sources.list.d/debian.sources
[ -f "$sources" ] && sed 's/^Types:.*/Types: deb-src/' "$sources" > "$apt_dir/parts/debian.sources"
# The one-line format, which Debian 12's installer and debootstrap write: its Debian lines.
[ -f /etc/apt/sources.list ] &&
  sed -nE 's#^[[:space:]]*deb[[:space:]]+((\[[^]]*\][[:space:]]+)?[^[:space:]]+/debian(-security)?/?[[:space:]].*)#deb-src \1#p' \
    /etc/apt/sources.list > "$apt_dir/parts/debian.list"
if [ ! -s "$apt_dir/parts/debian.sources" ] && [ ! -s "$apt_dir/parts/debian.list" ]; then
  echo "dqjulia deps: no Debian apt sources found (/etc/apt/sources.list.d/debian.sources, /etc/apt/sources.list)" >&2
  exit 1
fi
apt_opts=(-o Dir::Etc::sourcelist=/dev/null -o "Dir::Etc::sourceparts=$apt_dir/parts"
          -o "Dir::State::Lists=$apt_dir/lists" -o "Dir::Cache=$apt_dir/cache" -o APT::Sandbox::User=root)
apt-get "${apt_opts[@]}" -q update >/dev/null
# Only the upstream tarball (.orig) is needed; apt checks its hash against Debian's index.
# Some Debian parts (.debian.tar.xz, a security update's .dsc) may be missing from the mirror,
# and a security update's files may be missing altogether (zlib's): then the release's own
# source (PACKAGE/bookworm), whose upstream tarball is the same.
release=$(. /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-}")
fetch() {  # fetch PACKAGE ORIG_GLOB
  local orig="" source
  for source in "$1" ${release:+"$1/$release"}; do
    (cd "$work/src" && apt-get "${apt_opts[@]}" -q source --download-only "$source" >/dev/null 2>&1) || true
    orig=$(ls "$work/src"/$2 2>/dev/null | head -n 1 || true)
    [ -z "$orig" ] || break
  done
  if [ -z "$orig" ]; then
    echo "dqjulia deps: could not download the Debian source of $1 ($2)" >&2
    exit 1
  fi
  mkdir -p "$work/src/${1%%=*}"
  tar -xf "$orig" -C "$work/src/${1%%=*}" --strip-components=1
  # Where it came from, for the notices: the Debian source's version (its .dsc, when the mirror
  # has it) and the upstream tarball apt checked against Debian's index.
  local dsc
  dsc=$(ls "$work/src/${1%%=*}"_*.dsc 2>/dev/null | head -n 1 || true)
  {
    echo "Debian source package: ${1%%=*}${dsc:+ $(basename "$dsc" .dsc | sed 's/^[^_]*_//')}"
    echo "Upstream tarball: $(basename "$orig") (SHA-256 $(sha256sum "$orig" | cut -d' ' -f1))"
  } > "$work/src/${1%%=*}.source"
}
# licences SOURCE FILE...: a component's licence and notice files (paths in its source tree)
# into share/licenses/SOURCE/ of the prefix, with its SOURCE record; names flattened (a/b -> a-b).
licences() {
  local source=$1 file
  shift
  mkdir -p "$stage/share/licenses/$source"
  cp "$work/src/$source.source" "$stage/share/licenses/$source/SOURCE"
  for file in "$@"; do
    cp "$work/src/$source/$file" "$stage/share/licenses/$source/${file//\//-}" \
      || { echo "dqjulia deps: $source has no licence file $file" >&2; exit 1; }
  done
}
# system_licence NAME PACKAGE [DEP5_LICENSE]: the copyright file of an installed Debian package
# (the toolchain's runtime libraries, Boost's headers) into share/licenses/NAME/; with
# DEP5_LICENSE only that licence's stand-alone paragraph of it (Boost's file has 46,000 lines).
system_licence() {
  local name=$1 package=$2 licence=${3:-} copyright=/usr/share/doc/$2/copyright
  mkdir -p "$stage/share/licenses/$name"
  dpkg-query -W -f 'Debian package: ${Package} ${Version} (source ${source:Package} ${source:Version})\n' "$package" \
    > "$stage/share/licenses/$name/SOURCE" \
    || { echo "dqjulia deps: the Debian package $package is not installed" >&2; exit 1; }
  if [ -z "$licence" ]; then
    cp "$copyright" "$stage/share/licenses/$name/copyright"
  else  # the paragraph "License: NAME" followed by its text (lines starting with a space)
    awk -v want="License: $licence" '{ if (on && /^ /) print; else on = (prev == "" && $0 == want); prev = $0 }' \
      "$copyright" | sed 's/^ \.$//; s/^ //' > "$stage/share/licenses/$name/$licence.txt"
    [ -s "$stage/share/licenses/$name/$licence.txt" ] \
      || { echo "dqjulia deps: no $licence text in $copyright" >&2; exit 1; }
  fi
}
fetch zlib 'zlib_1.2.13*.orig.tar.*'
fetch libpng1.6 'libpng1.6_1.6.39.orig.tar.*'
fetch imath 'imath_3.1.6.orig.tar.*'
fetch openexr 'openexr_3.1.5.orig.tar.*'
fetch onetbb 'onetbb_2021.8.0.orig.tar.*'
fetch highway 'highway_1.0.3.orig.tar.*'
fetch lz4 'lz4_1.9.4.orig.tar.*'
fetch c-blosc 'c-blosc_1.21.3*.orig.tar.*'
fetch openvdb 'openvdb_10.0.1.orig.tar.*'
fetch freetype 'freetype_2.12.1*.orig.tar.*'
fetch glm 'glm_0.9.9.8*.orig.tar.*'
fetch nlohmann-json3 'nlohmann-json3_3.11.2.orig.tar.*'
fetch cli11 'cli11_2.1.2*.orig.tar.*'
# oneTBB: a thread the system refuses (ulimit -u, ulimit -v) means fewer threads, and a task's
# exception without memory to hold it a bad_alloc, not std::terminate (each patch says why).
for fix in thread-launch-failures exception-out-of-memory; do
  patch -d "$work/src/onetbb" -p1 --quiet < "$here/patches/onetbb-2021.8.0-$fix.patch" \
    || { echo "dqjulia deps: patching oneTBB ($fix) failed" >&2; exit 1; }
done
# OpenVDB's readers made safe for damaged files, and its accessors for exhausted memory (each
# patch says what and why).
for fix in compression-bounds read-bools node-origins read-failures accessor-registration; do
  patch -d "$work/src/openvdb" -p1 --quiet < "$here/patches/openvdb-10.0.1-$fix.patch" \
    || { echo "dqjulia deps: patching OpenVDB ($fix) failed" >&2; exit 1; }
done
if [ "$target" = windows-x64 ]; then
  fetch googletest 'googletest_1.12.1.orig.tar.*'
fi
log "sources fetched"
# The temporary folder's paths (in assertion messages, __FILE__) become a fixed name.
prefix_map="-ffile-prefix-map=$work=/usr/src/dqjulia-deps"
export CFLAGS="$prefix_map" CXXFLAGS="$prefix_map"

common=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_POSITION_INDEPENDENT_CODE=ON -DBUILD_SHARED_LIBS=OFF
        "-DCMAKE_INSTALL_PREFIX=$stage" "-DCMAKE_PREFIX_PATH=$stage" -DCMAKE_INSTALL_LIBDIR=lib
        -DCMAKE_POLICY_VERSION_MINIMUM=3.5)
if [ "$target" = windows-x64 ]; then
  common+=("-DCMAKE_TOOLCHAIN_FILE=$here/../cmake/toolchains/mingw-w64-x86_64.cmake" "-DDQJ_DEPS_PREFIX=$stage")
fi
build() {  # build NAME [CMAKE OPTIONS...]
  local name=$1
  shift
  "$cmake_bin" -S "$work/src/$name" -B "$work/build/$name" "${common[@]}" "$@" >"$work/$name.log" 2>&1 \
    && "$cmake_bin" --build "$work/build/$name" -j"$jobs" >>"$work/$name.log" 2>&1 \
    && "$cmake_bin" --install "$work/build/$name" >>"$work/$name.log" 2>&1 \
    || { tail -n 40 "$work/$name.log" >&2; echo "dqjulia deps: building $name failed" >&2; exit 1; }
  log "built $name"
}

# zlib: its own configure makes only the static archive (CHOST: for MinGW).
zlib_env=(CFLAGS="-O2 -fPIC $prefix_map")
[ "$target" = windows-x64 ] && zlib_env=(CHOST=$mingw CC=$mingw-gcc-posix CFLAGS="-O2 $prefix_map")
(cd "$work/src/zlib" && env "${zlib_env[@]}" ./configure --static --prefix="$stage" >"$work/zlib.log" 2>&1 \
  && make -j"$jobs" libz.a >>"$work/zlib.log" 2>&1 && make install >>"$work/zlib.log" 2>&1) \
  || { tail -n 40 "$work/zlib.log" >&2; echo "dqjulia deps: building zlib failed" >&2; exit 1; }
log "built zlib"
zlib_opts=("-DZLIB_ROOT=$stage" "-DZLIB_LIBRARY=$stage/lib/libz.a" "-DZLIB_INCLUDE_DIR=$stage/include")

# LZ4: its own Makefile's static archive alone (its CMake builds the command too), for c-blosc.
lz4_env=(CFLAGS="-O2 -fPIC $prefix_map")
[ "$target" = windows-x64 ] && lz4_env=(CC=$mingw-gcc-posix AR=$mingw-ar CFLAGS="-O2 $prefix_map")
(cd "$work/src/lz4/lib" && env "${lz4_env[@]}" make -j"$jobs" liblz4.a >"$work/lz4.log" 2>&1 \
  && mkdir -p "$stage/lib" "$stage/include" && cp liblz4.a "$stage/lib/" \
  && cp lz4.h lz4hc.h lz4frame.h "$stage/include/") \
  || { tail -n 40 "$work/lz4.log" >&2; echo "dqjulia deps: building lz4 failed" >&2; exit 1; }
log "built lz4"

openvdb_opts=()
if [ "$target" = windows-x64 ]; then
  # OpenVDB's headers include Boost's (header-only here): the system's, through a link in the
  # prefix (adding /usr/include itself would mix Linux headers into the MinGW build). On WIN32
  # its CMake links Boost::disable_autolinking, which only find_package(Boost) defines, and
  # nothing finds Boost without delayed loading: an injected file defines it.
  if [ ! -d /usr/include/boost ]; then
    echo "dqjulia deps: the Boost headers are missing: install libboost-dev (scripts/install-deps.sh)" >&2
    exit 1
  fi
  mkdir -p "$stage/include"
  ln -s /usr/include/boost "$stage/include/boost"
  cat > "$work/boost-headers.cmake" <<EOF
if(NOT TARGET Boost::disable_autolinking)  # included after each of OpenVDB's project() calls
  add_library(Boost::disable_autolinking INTERFACE IMPORTED)
  set_target_properties(Boost::disable_autolinking PROPERTIES INTERFACE_COMPILE_DEFINITIONS BOOST_ALL_NO_LIB
                        INTERFACE_INCLUDE_DIRECTORIES "$stage/include")
endif()
EOF
  openvdb_opts=("-DCMAKE_PROJECT_INCLUDE=$work/boost-headers.cmake")
fi

build libpng1.6 "${zlib_opts[@]}" -DPNG_SHARED=OFF -DPNG_STATIC=ON -DPNG_TESTS=OFF -DPNG_EXECUTABLES=OFF
build imath -DBUILD_TESTING=OFF -DPYTHON=OFF
build openexr "${zlib_opts[@]}" -DBUILD_TESTING=OFF -DOPENEXR_BUILD_TOOLS=OFF -DOPENEXR_INSTALL_EXAMPLES=OFF \
  -DOPENEXR_INSTALL_TOOLS=OFF -DOPENEXR_INSTALL_PKG_CONFIG=OFF
build onetbb -DTBB_TEST=OFF -DTBB_STRICT=OFF -DTBB_EXAMPLES=OFF -DTBBMALLOC_BUILD=OFF
if [ "$target" = windows-x64 ]; then
  # MinGW's oneTBB marks its functions dllexport (as linker directives in each object, its only
  # ones): linked in statically they would be exported from dqjulia.dll and dqjulia.exe too.
  $mingw-objcopy --remove-section=.drectve "$stage/lib/libtbb12.a"
fi
build highway -DHWY_ENABLE_TESTS=OFF -DHWY_ENABLE_EXAMPLES=OFF -DHWY_ENABLE_CONTRIB=OFF -DHWY_ENABLE_INSTALL=ON \
  -DHWY_FORCE_STATIC_LIBS=ON -DBUILD_TESTING=OFF
# batch.cpp's vector exp and log: the header-only hwy/contrib/math (the contrib libraries unbuilt;
# Debian's libhwy-dev has it, a fresh machine does not).
mkdir -p "$stage/include/hwy/contrib/math"
cp "$work/src/highway/hwy/contrib/math/"*.h "$stage/include/hwy/contrib/math/"
# c-blosc with our LZ4 and zlib named by path (the system's libblosc-dev or liblz4 must not be
# found), static only, its symbols hidden (HIDE_SYMBOLS: no export attribute in a static build).
# MinGW: its shuffle.c calls _xgetbv (behind a CPUID check), an intrinsic GCC allows only with
# -mxsave (CFLAGS joins the toolchain's flags rather than replacing them).
blosc_cflags=$prefix_map
[ "$target" = windows-x64 ] && blosc_cflags="$prefix_map -mxsave"
CFLAGS=$blosc_cflags build c-blosc "${zlib_opts[@]}" -DBUILD_SHARED=OFF -DBUILD_STATIC=ON -DBUILD_TESTS=OFF \
  -DBUILD_FUZZERS=OFF -DBUILD_BENCHMARKS=OFF -DHIDE_SYMBOLS=ON -DPREFER_EXTERNAL_LZ4=ON \
  "-DLZ4_INCLUDE_DIR=$stage/include" "-DLZ4_LIBRARY=$stage/lib/liblz4.a" -DPREFER_EXTERNAL_ZLIB=ON \
  -DDEACTIVATE_ZSTD=ON -DDEACTIVATE_SNAPPY=ON
if [ "$target" = windows-x64 ]; then
  # On Windows blosc.c compiles in its own pthread_create and pthread_cond_* (win32/pthread.c),
  # global symbols that would clash with winpthreads' in a static link: renamed in the archive.
  renames=()
  for sym in die pthread_create pthread_cond_init pthread_cond_destroy pthread_cond_wait pthread_cond_signal \
             pthread_cond_broadcast win32_pthread_join; do
    renames+=(--redefine-sym "$sym=dqj_blosc_$sym")
  done
  $mingw-objcopy "${renames[@]}" "$stage/lib/libblosc.a"
fi
build openvdb "${zlib_opts[@]}" "-DTBB_ROOT=$stage" -DOPENVDB_CORE_SHARED=OFF -DOPENVDB_CORE_STATIC=ON \
  -DOPENVDB_BUILD_BINARIES=OFF -DOPENVDB_BUILD_PYTHON_MODULE=OFF -DOPENVDB_BUILD_UNITTESTS=OFF \
  -DOPENVDB_BUILD_DOCS=OFF -DUSE_BLOSC=ON "-DBlosc_ROOT=$stage" "-DBlosc_INCLUDE_DIR=$stage/include" \
  "-DBlosc_LIBRARY_RELEASE=$stage/lib/libblosc.a" "-DBlosc_LIBRARY_DEBUG=$stage/lib/libblosc.a" -DUSE_ZLIB=ON \
  -DUSE_EXPLICIT_INSTANTIATION=OFF \
  -DOPENVDB_USE_DELAYED_LOADING=OFF -DUSE_PKGCONFIG=OFF "${openvdb_opts[@]}"

# FreeType with our zlib (without it, it compiles a copy of zlib in, whose symbols clash with it).
build freetype "${zlib_opts[@]}" -DFT_REQUIRE_ZLIB=ON -DFT_DISABLE_BZIP2=ON -DFT_DISABLE_PNG=ON \
  -DFT_DISABLE_HARFBUZZ=ON -DFT_DISABLE_BROTLI=ON
if [ "$target" = windows-x64 ]; then
  build googletest -DBUILD_GMOCK=OFF -DINSTALL_GTEST=ON
  build nlohmann-json3 -DJSON_BuildTests=OFF -DJSON_Install=ON
  build cli11 -DCLI11_BUILD_TESTS=OFF -DCLI11_BUILD_EXAMPLES=OFF -DCLI11_BUILD_DOCS=OFF -DCLI11_INSTALL=ON
  # GLM 0.9.9.8 has no install rule; its source tree's cmake/glm/glmConfig.cmake finds the headers
  # beside it, and find_package looks in <prefix>/glm/cmake/glm/. It asks for CMake 3.2, which
  # CMake 4 refuses: allowed up to 3.25's policies.
  mkdir -p "$stage/glm"
  cp -r "$work/src/glm/glm" "$work/src/glm/cmake" "$stage/glm/"
  sed -i 's/^\(cmake_minimum_required(VERSION\|cmake_policy(VERSION\) 3\.2/\1 3.2...3.25/' \
    "$stage/glm/cmake/glm/glmConfig.cmake"
  log "installed glm"
fi

# Licences (see the top): each component's from its source, the toolchain's from its packages.
licences zlib LICENSE
licences libpng1.6 LICENSE
licences imath LICENSE.md
licences openexr LICENSE.md
# oneTBB's third-party file holds the notices of the code it includes (ITT notify among them).
licences onetbb LICENSE.txt third-party-programs.txt
licences highway LICENSE
licences lz4 lib/LICENSE
# c-blosc's own, and of the code compiled into it: bitshuffle and FastLZ (blosclz). Its codecs
# are our LZ4 and zlib (their own entries); Snappy, Zstd and the MSVC stdint.h are not built.
licences c-blosc LICENSES/BLOSC.txt LICENSES/BITSHUFFLE.txt LICENSES/FASTLZ.txt
licences openvdb LICENSE
# FreeType under the FreeType License (of its two); its BDF and PCF drivers' licences.
licences freetype LICENSE.TXT docs/FTL.TXT src/bdf/README src/pcf/README
licences glm copying.txt
licences nlohmann-json3 LICENSE.MIT
licences cli11 LICENSE
system_licence boost "$(dpkg -S /usr/include/boost/version.hpp | cut -d: -f1)" BSL-1.0  # libboost1.74-dev
if [ "$target" = windows-x64 ]; then
  system_licence gcc-runtime gcc-mingw-w64-base          # libstdc++, libgcc (GCC Runtime Library Exception)
  system_licence mingw-w64-runtime mingw-w64-x86-64-dev  # the C runtime's startup code, winpthreads
else
  system_licence gcc-runtime "gcc-$(c++ -dumpversion | cut -d. -f1)-base"  # libstdc++, libgcc
fi

echo "$versions" > "$stage/.complete"
rm -rf "$prefix"
mv "$stage" "$prefix"
log "done: $prefix"
echo "$prefix"
