# Copies the SPIR-V modules that raybridge_embed_shaders compiled into one folder, the input of a build
# configured with -DRAYBRIDGE_PREBUILT_SPIRV=ON -DRAYBRIDGE_SPIRV_DIR=<that folder>.
# Run by the raybridge_export_spirv target, or by hand after building the SDK:
#   cmake -DMANIFEST=<build>/sdk/embedded_shaders/raybridge/spirv_files.txt -DDEST=<folder> -P cmake/ExportSpirv.cmake
file(STRINGS ${MANIFEST} files)
if(NOT files)
  message(FATAL_ERROR "${MANIFEST} lists no SPIR-V files")
endif()
file(MAKE_DIRECTORY ${DEST})
foreach(f ${files})
  if(NOT EXISTS ${f})
    message(FATAL_ERROR "${f} has not been compiled yet; build the SDK first")
  endif()
  file(COPY ${f} DESTINATION ${DEST})
endforeach()
list(LENGTH files n)
message(STATUS "Wrote ${n} SPIR-V modules to ${DEST}")
