# Turns one SPIR-V binary into `inline constexpr uint32_t <NAME>[] = {...};`, a definition that a header can
# include into several translation units.
# Inputs: -DIN=<module.spv> -DOUT=<name.inc> -DNAME=<variable name>
file(READ ${IN} bytes HEX)
string(LENGTH "${bytes}" hex_len)
math(EXPR rest "${hex_len} % 8")
if(hex_len EQUAL 0 OR NOT rest EQUAL 0)
  message(FATAL_ERROR "${IN} is not SPIR-V: its size is not a whole number of 32-bit words")
endif()
# SPIR-V words are stored little-endian by glslang; the magic number 0x07230203 proves the order.
if(NOT bytes MATCHES "^03022307")
  message(FATAL_ERROR "${IN} is not little-endian SPIR-V (magic number missing)")
endif()
string(REGEX REPLACE "(..)(..)(..)(..)" "0x\\4\\3\\2\\1," words "${bytes}")
# Eight words per line keeps the generated file readable in a diff.
string(REPEAT "0x........," 8 line)
string(REGEX REPLACE "(${line})" "\\1\n" words "${words}")
get_filename_component(spv_name ${IN} NAME)
file(WRITE ${OUT} "// Generated from ${spv_name}\ninline constexpr uint32_t ${NAME}[] = {\n${words}\n};\n")
