# cmake -DIN=file -DOUT=header -P Embed.cmake: writes the file as a raw string constant.
file(READ ${IN} CONTENT)
file(WRITE ${OUT} "#pragma once\n// Generated from ${IN}; do not edit.\nnamespace foresight {\ninline constexpr const char* kEmbeddedDefaultConfig = R\"FORESIGHT_EMBED(${CONTENT})FORESIGHT_EMBED\";\n}\n")
