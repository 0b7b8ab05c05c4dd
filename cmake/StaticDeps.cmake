# The third-party libraries libdqjulia links statically: built from Debian 12's source packages
# by scripts/build-deps.sh into a cache outside the checkout (DQJ_DEPS_PREFIX). Each becomes an
# imported target dqj::<name> naming its archive by path, so nothing of the system's shared
# OpenVDB, TBB or OpenEXR can slip into the link.
#
#   dqj::zlib dqj::png dqj::imath dqj::openexr dqj::tbb dqj::hwy dqj::lz4 dqj::blosc dqj::openvdb
#   dqj::freetype
#
# (c-blosc, with LZ4 and zlib as its codecs, is OpenVDB's Blosc compression of the files it writes;
# FreeType draws the command's contact sheet labels and is not in libdqjulia.)
#
# The global property DQJ_STATIC_DEPENDENCY_ARCHIVES lists their archives' file names (for
# the linker's --exclude-libs).

if(NOT DQJ_DEPS_PREFIX)
  execute_process(COMMAND ${PROJECT_SOURCE_DIR}/scripts/build-deps.sh --print
                  OUTPUT_VARIABLE dqj_deps_default OUTPUT_STRIP_TRAILING_WHITESPACE)
  set(DQJ_DEPS_PREFIX "${dqj_deps_default}" CACHE PATH
      "The static third-party libraries (scripts/build-deps.sh prints and builds this folder)")
endif()
if(NOT EXISTS "${DQJ_DEPS_PREFIX}/.complete")
  message(FATAL_ERROR "dqjulia: the static third-party libraries are not built at ${DQJ_DEPS_PREFIX}.\n"
                      "Run scripts/build-deps.sh (about 8 minutes once; cached outside the checkout), "
                      "or set DQJ_DEPS_PREFIX to a folder it made.")
endif()
message(STATUS "dqjulia: static third-party libraries from ${DQJ_DEPS_PREFIX}")

find_package(Threads REQUIRED)
set(dqj_deps_include "${DQJ_DEPS_PREFIX}/include")

# dqj_static_dependency(NAME ARCHIVES... [LINKS targets...] [INCLUDES dirs...] [DEFINES defs...])
function(dqj_static_dependency name)
  cmake_parse_arguments(PARSE_ARGV 1 arg "" "" "ARCHIVES;LINKS;INCLUDES;DEFINES")
  set(archives)
  foreach(archive IN LISTS arg_ARCHIVES)
    set(path "${DQJ_DEPS_PREFIX}/lib/${archive}")
    if(NOT EXISTS "${path}")
      message(FATAL_ERROR "dqjulia: ${path} is missing: rebuild with scripts/build-deps.sh")
    endif()
    list(APPEND archives "${path}")
    set_property(GLOBAL APPEND PROPERTY DQJ_STATIC_DEPENDENCY_ARCHIVES "${archive}")
  endforeach()
  list(POP_FRONT archives first)
  add_library(dqj::${name} STATIC IMPORTED GLOBAL)
  set_target_properties(dqj::${name} PROPERTIES
    IMPORTED_LOCATION "${first}"
    INTERFACE_INCLUDE_DIRECTORIES "${dqj_deps_include};${arg_INCLUDES}"
    INTERFACE_LINK_LIBRARIES "${archives};${arg_LINKS}"
    INTERFACE_COMPILE_DEFINITIONS "${arg_DEFINES}")
endfunction()

dqj_static_dependency(zlib ARCHIVES libz.a)
dqj_static_dependency(png ARCHIVES libpng16.a LINKS dqj::zlib m)
dqj_static_dependency(imath ARCHIVES libImath-3_1.a LINKS m INCLUDES "${dqj_deps_include}/Imath")
dqj_static_dependency(openexr
  ARCHIVES libOpenEXR-3_1.a libOpenEXRUtil-3_1.a libOpenEXRCore-3_1.a libIlmThread-3_1.a libIex-3_1.a
  LINKS dqj::imath dqj::zlib Threads::Threads INCLUDES "${dqj_deps_include}/OpenEXR")
if(WIN32)  # MinGW-w64 (cmake/toolchains/mingw-w64-x86_64.cmake): oneTBB's Windows name; OpenVDB's static-use defines
  dqj_static_dependency(tbb ARCHIVES libtbb12.a LINKS Threads::Threads)
  set(dqj_openvdb_defines OPENVDB_STATICLIB _USE_MATH_DEFINES)
else()
  dqj_static_dependency(tbb ARCHIVES libtbb.a LINKS Threads::Threads ${CMAKE_DL_LIBS} rt)
  set(dqj_openvdb_defines)
endif()
dqj_static_dependency(hwy ARCHIVES libhwy.a DEFINES HWY_STATIC_DEFINE)
dqj_static_dependency(lz4 ARCHIVES liblz4.a)
dqj_static_dependency(blosc ARCHIVES libblosc.a LINKS dqj::lz4 dqj::zlib Threads::Threads)
dqj_static_dependency(openvdb ARCHIVES libopenvdb.a LINKS dqj::tbb dqj::imath dqj::blosc dqj::zlib Threads::Threads
                      DEFINES ${dqj_openvdb_defines})
dqj_static_dependency(freetype ARCHIVES libfreetype.a LINKS dqj::zlib INCLUDES "${dqj_deps_include}/freetype2")
