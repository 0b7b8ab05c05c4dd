# Sourced by build.sh and test.sh: sets DQJ_LAUNCHER to CMake's compiler-launcher options when
# ccache is installed (an empty list otherwise). The cache lives outside the checkout
# (ccache's default, ~/.cache/ccache) and paths are taken relative to the checkout, so a fresh
# clone in another folder reuses it. It only saves time: without it everything builds anyway.
DQJ_LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then
  # The sanitizer build's ignore list is an absolute path: left out of the hash (its MD5 is in a
  # definition instead, CMakeLists.txt), so it does not make every clone miss. So are the
  # -ffile-prefix-map options (CMakeLists.txt), which name the checkout: the compiler sees the
  # checkout's paths relative (base_dir), so there they map nothing, and the deps prefix they also
  # map is hashed through the -I options; change their new names and the cache must be cleared.
  launcher="env;CCACHE_BASEDIR=$PWD;CCACHE_NOHASHDIR=1;CCACHE_IGNOREOPTIONS=-fsanitize-ignorelist=* -ffile-prefix-map=*;ccache"
  DQJ_LAUNCHER=("-DCMAKE_C_COMPILER_LAUNCHER=$launcher" "-DCMAKE_CXX_COMPILER_LAUNCHER=$launcher")
fi
