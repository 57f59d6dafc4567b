# Writes SPIR-V module SPV as a C header HDR holding `const uint32_t NAME[]`.
# Usage: cmake -DSPV=in.spv -DHDR=out.spv.h -DNAME=pb_spv_x -P spirv_embed.cmake
# (the optimized module comes from spirv-opt, which writes no header, and
# glslang's --vn can only embed what glslang compiled itself)
file(READ "${SPV}" hex HEX)
string(LENGTH "${hex}" n)
math(EXPR rem "${n} % 8")
if(n EQUAL 0 OR NOT rem EQUAL 0)
  message(FATAL_ERROR "${SPV}: not a SPIR-V module (${n} hex digits)")
endif()
# SPIR-V files are little-endian words: bytes b0 b1 b2 b3 -> 0xb3b2b1b0
string(REGEX REPLACE "(..)(..)(..)(..)" "0x\\4\\3\\2\\1," words "${hex}")
set(w "0x........,") # CMake's regular expressions have no {n}
string(REGEX REPLACE "(${w}${w}${w}${w}${w}${w}${w}${w})" "\\1\n    " words "${words}")
file(WRITE "${HDR}" "// generated from ${SPV} by scripts/spirv_embed.cmake\n#pragma once\n#include <stdint.h>\n"
                    "const uint32_t ${NAME}[] = {\n    ${words}\n};\n")
