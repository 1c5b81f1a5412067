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
