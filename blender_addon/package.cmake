# Stages the add-on and zips it (run by the blender_addon target):
#   dqjulia/            the Python package, shaders/ and blender_manifest.toml
#   dqjulia/_buildinfo.py
#   dqjulia/native.py   the ctypes bindings: NATIVE (python/dqjulia/_native.py), the Python package's, unchanged
#   dqjulia/presets/    examples/*.json
#   dqjulia/schema.json the parameter schema (dqjulia schema), which props.py builds the properties from
#   dqjulia/lib/LIBRARY_NAME    the real library file (not a symlink), stripped: libdqjulia.so, or
#                               dqjulia.dll in the Windows zip (PLATFORM windows-x64, the manifest's
#                               platforms; EMULATOR runs the Windows dqjulia schema)
#   dqjulia/LICENSE, dqjulia/THIRD-PARTY-NOTICES.txt    from LICENSES (build/licenses/)
# The zip is reproducible (scripts/pack.py: sorted entries, SOURCE_DATE_EPOCH's time, fixed modes).
cmake_minimum_required(VERSION 3.25)
file(REMOVE_RECURSE "${STAGE}")
file(MAKE_DIRECTORY "${STAGE}/dqjulia/lib" "${STAGE}/dqjulia/presets")
file(COPY "${SOURCE}/" DESTINATION "${STAGE}/dqjulia"
     PATTERN "__pycache__" EXCLUDE PATTERN "*.pyc" EXCLUDE)
file(COPY "${BUILDINFO}" DESTINATION "${STAGE}/dqjulia")
file(COPY_FILE "${NATIVE}" "${STAGE}/dqjulia/native.py")
# The project's version (VERSION) into the manifest (4.2+) and bl_info (3.4 - 4.1), which Blender
# reads as literals without running the add-on. tests/version/version_test.py checks the zip's.
string(REPLACE "." ", " version_tuple "${VERSION}")
file(READ "${STAGE}/dqjulia/blender_manifest.toml" text)
string(REGEX REPLACE "\nversion = \"[0-9.]+\"" "\nversion = \"${VERSION}\"" text "${text}")
string(REGEX REPLACE "\nplatforms = \\[[^]\n]*\\]" "\nplatforms = [\"${PLATFORM}\"]" text "${text}")
file(WRITE "${STAGE}/dqjulia/blender_manifest.toml" "${text}")
file(READ "${STAGE}/dqjulia/__init__.py" text)
string(REGEX REPLACE "\"version\": \\([0-9, ]+\\)" "\"version\": (${version_tuple})" text "${text}")
file(WRITE "${STAGE}/dqjulia/__init__.py" "${text}")
file(GLOB examples "${EXAMPLES}/*.json")
file(COPY ${examples} DESTINATION "${STAGE}/dqjulia/presets")
# The schema the properties are built from, written by the core (tests/blender check it against
# the library loaded and the properties registered).
execute_process(COMMAND ${EMULATOR} "${CLI}" schema OUTPUT_FILE "${STAGE}/dqjulia/schema.json" RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "could not write the parameter schema (dqjulia schema)")
endif()
file(COPY_FILE "${LIBRARY}" "${STAGE}/dqjulia/lib/${LIBRARY_NAME}")
if(STRIP)  # the symbol table is for debuggers; the dynamic symbols (dqj_*) and the DLL's exports stay
  execute_process(COMMAND "${STRIP}" --strip-unneeded "${STAGE}/dqjulia/lib/${LIBRARY_NAME}" RESULT_VARIABLE result)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "could not strip ${STAGE}/dqjulia/lib/${LIBRARY_NAME}")
  endif()
endif()
file(COPY "${LICENSES}/LICENSE" "${LICENSES}/THIRD-PARTY-NOTICES.txt" DESTINATION "${STAGE}/dqjulia")
get_filename_component(zip_dir "${ZIP}" DIRECTORY)
file(MAKE_DIRECTORY "${zip_dir}")
execute_process(COMMAND "${PYTHON}" "${PACK}" zip "${ZIP}" "${STAGE}/dqjulia" RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "could not write ${ZIP}")
endif()
