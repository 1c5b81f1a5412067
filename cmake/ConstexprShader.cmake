# Rewrites in place what glslangValidator --vn writes: `const uint32_t name[] = {...};`; make it `inline constexpr` so a header that
# includes it can be used from several translation units.
file(READ ${IN} text)
string(REPLACE "const uint32_t" "inline constexpr uint32_t" text "${text}")
string(REGEX REPLACE "#pragma once\n" "" text "${text}")
file(WRITE ${OUT} "${text}")
