# Installs the already built Raybridge into a scratch prefix, then configures, builds and runs the consumer
# project's programs against it with find_package(Raybridge): one without Vulkan calls of its own, one on the
# loader's prototypes, one on its own volk.
# Inputs: -DBUILD_DIR=<raybridge build dir> -DSOURCE_DIR=<this folder> -DWORK_DIR=<scratch dir>
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix
                RESULT_VARIABLE r OUTPUT_QUIET)
if(r)
  message(FATAL_ERROR "installing Raybridge failed (${r})")
endif()
# What the package holds: the public headers (the SDK's and the headless device's), the public GLSL, the library
# with its embedded SPIR-V and the CMake package; no internal header or shader.
get_filename_component(raybridge_root ${SOURCE_DIR}/../.. ABSOLUTE)
file(GLOB want_headers RELATIVE ${raybridge_root}/sdk/include/raybridge ${raybridge_root}/sdk/include/raybridge/*.h)
list(APPEND want_headers headless_device.h)
file(GLOB got_headers RELATIVE ${WORK_DIR}/prefix/include/raybridge ${WORK_DIR}/prefix/include/raybridge/*)
list(SORT want_headers)
list(SORT got_headers)
if(NOT want_headers STREQUAL got_headers)
  message(FATAL_ERROR "installed headers differ from the public ones:\n want ${want_headers}\n got  ${got_headers}")
endif()
# The public GLSL is the folder shaders/public, installed as share/raybridge/shaders.
file(GLOB want_glsl RELATIVE ${raybridge_root}/shaders/public ${raybridge_root}/shaders/public/*)
list(TRANSFORM want_glsl PREPEND share/raybridge/shaders/)
file(GLOB_RECURSE got_glsl RELATIVE ${WORK_DIR}/prefix ${WORK_DIR}/prefix/*.glsl ${WORK_DIR}/prefix/*.rgen
     ${WORK_DIR}/prefix/*.comp ${WORK_DIR}/prefix/*.rchit ${WORK_DIR}/prefix/*.rahit ${WORK_DIR}/prefix/*.rmiss
     ${WORK_DIR}/prefix/share/raybridge/shaders/*)
list(REMOVE_DUPLICATES got_glsl)
list(SORT want_glsl)
list(SORT got_glsl)
if(NOT want_glsl OR NOT want_glsl STREQUAL got_glsl)
  message(FATAL_ERROR "installed shaders are not the public GLSL alone (shaders/public):\n want ${want_glsl}\n"
                      " got  ${got_glsl}")
endif()
list(FIND got_glsl share/raybridge/shaders/raybridge_gbuffer.glsl gbuffer_glsl)
if(gbuffer_glsl EQUAL -1)
  message(FATAL_ERROR "the G-buffer encoders (raybridge_gbuffer.glsl) were not installed: ${got_glsl}")
endif()
file(GLOB libraries ${WORK_DIR}/prefix/lib*/libraybridge.a ${WORK_DIR}/prefix/lib*/libraybridge.so)
if(NOT libraries)
  message(FATAL_ERROR "the library (with the SPIR-V embedded) was not installed")
endif()

execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G Ninja
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release
                RESULT_VARIABLE r)
if(r)
  message(FATAL_ERROR "configuring the consumer against the installed package failed (${r})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/build RESULT_VARIABLE r)
if(r)
  message(FATAL_ERROR "building the consumer failed (${r})")
endif()
foreach(program consumer consumer_prototypes consumer_volk)
  execute_process(COMMAND ${WORK_DIR}/build/${program} RESULT_VARIABLE r)
  if(r)
    message(FATAL_ERROR "the ${program} program failed (${r})")
  endif()
endforeach()
