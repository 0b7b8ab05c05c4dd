# Writes a C++ source defining `const char* const NAME` in namespace dqj with the text of INPUT.
# Usage: cmake -DINPUT=file -DOUTPUT=file.cpp -DNAME=identifier -P EmbedText.cmake
# Used for povray/dqjulia.inc, which `dqjulia povray` copies beside the scenes it writes.
file(READ "${INPUT}" text)
# Raw string literals may not exceed what compilers accept in one piece: split into chunks
# of at most 8000 characters, concatenated by the compiler.
string(LENGTH "${text}" length)
set(chunks "")
set(offset 0)
while(offset LESS length)
  string(SUBSTRING "${text}" ${offset} 8000 chunk)
  string(APPEND chunks "R\"dqjembed(${chunk})dqjembed\"\n")
  math(EXPR offset "${offset} + 8000")
endwhile()
if(chunks STREQUAL "")
  set(chunks "\"\"")
endif()
file(WRITE "${OUTPUT}.tmp" "// Generated from ${INPUT} by core/cmake/EmbedText.cmake; do not edit.\nnamespace dqj {\nextern const char* const ${NAME};\nconst char* const ${NAME} =\n${chunks};\n}  // namespace dqj\n")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUTPUT}.tmp")
