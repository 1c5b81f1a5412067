# raybridge_embed_shaders(TARGET <target> NAMESPACE <c++ namespace> HEADER <name.h>
#                         [SOURCES <glsl files...>] [VARIANTS <rows...>] [BASE_DIR <dir>]
#                         [INCLUDE_DIRS <dirs...>] [PREBUILT_SPIRV_DIR <dir>] [EXPORT_TARGET <name> EXPORT_DIR <dir>])
# Generates one header that holds every module as a `constexpr uint32_t` array, so the program that links
# <target> ships no shader files. The variable name is the module name with '.' replaced by '_'
# (shadow.rgen -> shadow_rgen).
# A module is either a file of SOURCES, compiled as it is, its stage taken from its extension (shadow.rgen), or a
# row of VARIANTS: one body compiled with a set of defines. A row is three words,
#   <module name> <body file> <defines>
# where the module name's extension is the stage (ao_tiles.rgen -> glslangValidator -S rgen), the body is a GLSL
# file that starts with its own #version, and the defines are a comma-separated list (NAME or NAME=VALUE, passed
# as -D in that order) or "-" for none. A row compiles to exactly what a file holding `#version`, those
# `#define`s and `#include "<body>"` would.
# Relative SOURCES and bodies are taken from BASE_DIR (default: the current source folder).
# By default each module is compiled with glslangValidator at build time to <module name>.spv (shadow.rgen.spv);
# it is rebuilt when its file or body, or any file they include, changes (glslang's depfile).
# With PREBUILT_SPIRV_DIR the modules are read from <dir>/<module name>.spv instead and glslang is not needed.
# EXPORT_TARGET adds a target that copies the compiled .spv files into EXPORT_DIR (the input a prebuilt build
# reads); ${CMAKE_CURRENT_BINARY_DIR}/embedded_shaders/<target>/spirv_files.txt lists them for ExportSpirv.cmake.
function(raybridge_embed_shaders)
  cmake_parse_arguments(ARG "" "TARGET;NAMESPACE;HEADER;BASE_DIR;PREBUILT_SPIRV_DIR;EXPORT_TARGET;EXPORT_DIR"
                        "SOURCES;VARIANTS;INCLUDE_DIRS" ${ARGN})
  set(stages vert tesc tese geom frag comp rgen rint rahit rchit rmiss rcall mesh task)  # glslangValidator -S
  if(NOT ARG_BASE_DIR)
    set(ARG_BASE_DIR ${CMAKE_CURRENT_SOURCE_DIR})
  endif()
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/embedded_shaders/${ARG_TARGET})
  file(MAKE_DIRECTORY ${out_dir})
  if(NOT ARG_PREBUILT_SPIRV_DIR)
    # Looked up only here, so a build that embeds prebuilt SPIR-V never asks for glslang.
    find_program(GLSLANG_VALIDATOR glslangValidator REQUIRED)
  endif()
  set(include_flags)
  foreach(dir ${ARG_INCLUDE_DIRS})
    list(APPEND include_flags -I${dir})
  endforeach()

  # Every module as name, source file and extra glslang flags (the stage and defines of a variant).
  set(names)
  foreach(src ${ARG_SOURCES})
    get_filename_component(name ${src} NAME)
    get_filename_component(source_${name} ${src} ABSOLUTE BASE_DIR ${ARG_BASE_DIR})
    set(flags_${name})
    list(APPEND names ${name})
  endforeach()
  list(LENGTH ARG_VARIANTS n)
  math(EXPR rest "${n} % 3")
  if(NOT rest EQUAL 0)
    message(FATAL_ERROR "raybridge_embed_shaders(${ARG_TARGET}): VARIANTS takes rows of three words "
                        "(<module name> <body> <defines or ->), got ${n} words: ${ARG_VARIANTS}")
  endif()
  while(ARG_VARIANTS)
    list(POP_FRONT ARG_VARIANTS name body defines)
    if(name IN_LIST names)
      message(FATAL_ERROR "raybridge_embed_shaders(${ARG_TARGET}): the module ${name} is declared twice")
    endif()
    get_filename_component(stage ${name} LAST_EXT)
    string(SUBSTRING "${stage}" 1 -1 stage)
    if(NOT stage IN_LIST stages)
      message(FATAL_ERROR "raybridge_embed_shaders(${ARG_TARGET}): the variant ${name} must end in a stage "
                          "(${stages})")
    endif()
    get_filename_component(source_${name} ${body} ABSOLUTE BASE_DIR ${ARG_BASE_DIR})
    set(flags_${name} -S ${stage})
    if(NOT defines STREQUAL "-")
      string(REPLACE "," ";" defines "${defines}")
      foreach(define ${defines})
        list(APPEND flags_${name} -D${define})
      endforeach()
    endif()
    list(APPEND names ${name})
  endwhile()

  set(parts)
  set(spvs)
  foreach(name ${names})
    string(REPLACE "." "_" var ${name})
    set(part ${out_dir}/${var}.inc)
    if(ARG_PREBUILT_SPIRV_DIR)
      set(spv ${ARG_PREBUILT_SPIRV_DIR}/${name}.spv)
      if(NOT EXISTS ${spv})
        message(FATAL_ERROR "RAYBRIDGE_PREBUILT_SPIRV: ${spv} is missing; write it with the raybridge_export_spirv "
                            "target of a build that has glslang (see RAYBRIDGE_SPIRV_DIR)")
      endif()
    else()
      set(spv ${out_dir}/${name}.spv)
      add_custom_command(
        OUTPUT ${spv}
        COMMAND ${GLSLANG_VALIDATOR} --quiet --target-env vulkan1.2 ${include_flags} ${flags_${name}} -o ${spv}
                --depfile ${spv}.d ${source_${name}}
        DEPENDS ${source_${name}}
        DEPFILE ${spv}.d
        COMMENT "glslang ${name}"
        VERBATIM)
    endif()
    # The same conversion for compiled and prebuilt modules, so both embed identical arrays.
    add_custom_command(
      OUTPUT ${part}
      COMMAND ${CMAKE_COMMAND} -DIN=${spv} -DOUT=${part} -DNAME=${var} -P ${RAYBRIDGE_CMAKE_DIR}/ConstexprShader.cmake
      DEPENDS ${spv} ${RAYBRIDGE_CMAKE_DIR}/ConstexprShader.cmake
      COMMENT "embed ${name}"
      VERBATIM)
    list(APPEND parts ${part})
    list(APPEND spvs ${spv})
  endforeach()
  set(header ${out_dir}/${ARG_HEADER})
  set(content "// Generated by raybridge_embed_shaders: SPIR-V modules embedded at build time.\n#pragma once\n#include <cstdint>\nnamespace ${ARG_NAMESPACE} {\n")
  foreach(part ${parts})
    string(APPEND content "#include \"${part}\"\n")
  endforeach()
  string(APPEND content "}  // namespace ${ARG_NAMESPACE}\n")
  file(GENERATE OUTPUT ${header} CONTENT "${content}")
  target_sources(${ARG_TARGET} PRIVATE ${parts})
  target_include_directories(${ARG_TARGET} PRIVATE ${out_dir})

  if(ARG_EXPORT_TARGET AND NOT ARG_PREBUILT_SPIRV_DIR)
    set(manifest ${out_dir}/spirv_files.txt)
    string(REPLACE ";" "\n" manifest_text "${spvs}")
    file(WRITE ${manifest} "${manifest_text}\n")
    add_custom_target(${ARG_EXPORT_TARGET}
      COMMAND ${CMAKE_COMMAND} -DMANIFEST=${manifest} -DDEST=${ARG_EXPORT_DIR} -P ${RAYBRIDGE_CMAKE_DIR}/ExportSpirv.cmake
      DEPENDS ${spvs}
      COMMENT "Writing the SPIR-V of ${ARG_TARGET} to ${ARG_EXPORT_DIR}"
      VERBATIM)
  endif()
endfunction()
