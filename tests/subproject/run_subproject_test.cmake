# Builds the host project, which add_subdirectory()s the Raybridge sources, and checks that Raybridge leaks
# none of its own settings into it: the host's build type stands, the host's warnings are no errors, Raybridge's
# tests, samples and install rules are off. It embeds the SPIR-V that the parent build compiled
# (RAYBRIDGE_PREBUILT_SPIRV), which proves the glslang-free path gives the same modules.
# Inputs: -DBUILD_DIR=<raybridge build dir> -DRAYBRIDGE_SOURCE_DIR=<raybridge sources>
#         -DSOURCE_DIR=<this folder> -DWORK_DIR=<scratch dir>
file(REMOVE_RECURSE ${WORK_DIR})
set(embedded ${BUILD_DIR}/sdk/embedded_shaders/raybridge)

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE r OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(r)
    message(FATAL_ERROR "${what} failed (${r}):\n${out}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

# The modules a consumer without glslang would be handed.
run("exporting the SPIR-V of ${BUILD_DIR}"
    ${CMAKE_COMMAND} -DMANIFEST=${embedded}/spirv_files.txt -DDEST=${WORK_DIR}/spirv
    -P ${RAYBRIDGE_SOURCE_DIR}/cmake/ExportSpirv.cmake)

# A host that names no build type gets none from Raybridge.
run("configuring the host without a build type"
    ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/untyped -G Ninja -DRAYBRIDGE_SOURCE_DIR=${RAYBRIDGE_SOURCE_DIR}
    -DRAYBRIDGE_PREBUILT_SPIRV=ON -DRAYBRIDGE_SPIRV_DIR=${WORK_DIR}/spirv)
file(STRINGS ${WORK_DIR}/untyped/CMakeCache.txt build_type REGEX "^CMAKE_BUILD_TYPE:")
if(NOT build_type MATCHES "^CMAKE_BUILD_TYPE:STRING=$")
  message(FATAL_ERROR "Raybridge set a build type for a host that gave none: ${build_type}")
endif()

run("configuring the host"
    ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G Ninja -DRAYBRIDGE_SOURCE_DIR=${RAYBRIDGE_SOURCE_DIR}
    -DCMAKE_BUILD_TYPE=Debug -DCMAKE_EXPORT_COMPILE_COMMANDS=ON
    -DRAYBRIDGE_PREBUILT_SPIRV=ON -DRAYBRIDGE_SPIRV_DIR=${WORK_DIR}/spirv)
file(STRINGS ${WORK_DIR}/build/CMakeCache.txt build_type REGEX "^CMAKE_BUILD_TYPE:")
if(NOT build_type MATCHES "=Debug$")
  message(FATAL_ERROR "the host's build type changed: ${build_type}")
endif()
file(STRINGS ${WORK_DIR}/build/CMakeCache.txt glslang REGEX "^GLSLANG_VALIDATOR:")
if(glslang)
  message(FATAL_ERROR "a build with RAYBRIDGE_PREBUILT_SPIRV looked for glslang: ${glslang}")
endif()

# Only the host and what it links; Raybridge's own warnings stay on but not fatal.
run("building the host" ${CMAKE_COMMAND} --build ${WORK_DIR}/build --target host host_prototypes host_volk)
if(NOT out MATCHES "deliberately_unused_by_the_subproject_test")
  message(FATAL_ERROR "the host's deliberate warning was not reported, so the test proves nothing:\n${out}")
endif()
file(READ ${WORK_DIR}/build/compile_commands.json commands)
if(commands MATCHES "-Werror|/WX")
  message(FATAL_ERROR "warnings-as-errors leaked into the host's build:\n${commands}")
endif()

# The prebuilt modules embed exactly what the parent build compiled.
file(GLOB parts RELATIVE ${embedded} ${embedded}/*.inc)
if(NOT parts)
  message(FATAL_ERROR "no embedded modules in ${embedded}")
endif()
foreach(part ${parts})
  file(SHA256 ${embedded}/${part} want)
  file(SHA256 ${WORK_DIR}/build/raybridge/sdk/embedded_shaders/raybridge/${part} got)
  if(NOT want STREQUAL got)
    message(FATAL_ERROR "${part} embedded from prebuilt SPIR-V differs from the compiled one")
  endif()
endforeach()

run("installing the host" ${CMAKE_COMMAND} --install ${WORK_DIR}/build --prefix ${WORK_DIR}/prefix)
file(GLOB_RECURSE installed ${WORK_DIR}/prefix/*)
if(installed)
  message(FATAL_ERROR "Raybridge installed files from a host that asked for none: ${installed}")
endif()

foreach(program host host_prototypes host_volk)
  run("running ${program}" ${WORK_DIR}/build/${program})
  message(STATUS "${out}")
endforeach()
