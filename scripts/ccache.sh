# Sourced by build.sh and test.sh: sets DQJ_LAUNCHER to CMake's compiler-launcher options when
# ccache is installed (an empty list otherwise). The cache lives outside the checkout
# (ccache's default, ~/.cache/ccache) and paths are taken relative to the checkout, so a fresh
# clone in another folder reuses it. It only saves time: without it everything builds anyway.
DQJ_LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then
  # The sanitizer build's ignore list is an absolute path: left out of the hash (its MD5 is in a
  # definition instead, CMakeLists.txt), so it does not make every clone miss.
  launcher="env;CCACHE_BASEDIR=$PWD;CCACHE_NOHASHDIR=1;CCACHE_IGNOREOPTIONS=-fsanitize-ignorelist=*;ccache"
  DQJ_LAUNCHER=("-DCMAKE_C_COMPILER_LAUNCHER=$launcher" "-DCMAKE_CXX_COMPILER_LAUNCHER=$launcher")
fi
