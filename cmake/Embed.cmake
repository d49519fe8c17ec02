# cmake -DIN=file -DOUT=header [-DNAME=constant] -P Embed.cmake: writes the file as a raw string
# constant (NAME defaults to kEmbeddedDefaultConfig).
if(NOT DEFINED NAME)
  set(NAME kEmbeddedDefaultConfig)
endif()
file(READ ${IN} CONTENT)
file(WRITE ${OUT} "#pragma once\n// Generated from ${IN}; do not edit.\nnamespace foresight {\ninline constexpr const char* ${NAME} = R\"FORESIGHT_EMBED(${CONTENT})FORESIGHT_EMBED\";\n}\n")
