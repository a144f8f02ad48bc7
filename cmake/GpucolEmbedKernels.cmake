# Kernel embedding in the manner of OpenCV's cl2cpp: each opencl/kernels/<name>.cl is the only source of
# its kernels; at build time it becomes ${PROJECT_BINARY_DIR}/generated/gpucol_kernels/<name>.cpp, a C++
# string constant gpucol::opencl::kernels::<name>. Nothing generated is committed.
#
# `#include "<path>"` lines in a .cl, <path> relative to the repository root (opencl/shared/*.h, and the
# mathematics of plugin/src/shared_math/*.h, written to compile as both C++ and OpenCL C), are replaced
# by the text of that header, the same text the host compiles: the program needs no include path at run
# time and host and device always agree. A depfile lists the inlined headers, so editing one regenerates.
#
# Two halves: gpucol_embed_kernels() (configure time) sets up the custom commands; running this file with
# `cmake -P` and GPUCOL_EMBED_INPUT/OUTPUT/NAME/ROOT (build time) does one conversion.

if(CMAKE_SCRIPT_MODE_FILE)
  # Works on the whole text with regexes and string(REPLACE), never on CMake lists, because kernel code
  # is full of the ';' and '[' that CMake lists treat specially.
  file(READ "${GPUCOL_EMBED_INPUT}" text)
  set(inlined_headers "")
  set(pattern "#[ \t]*include[ \t]*\"([A-Za-z0-9_][A-Za-z0-9_/]*[.]h)\"")
  # Headers may include other shared headers: repeat until no include of a shared header is left. Each
  # header is inlined at its first include and dropped at later ones (include guards would do the same).
  while(text MATCHES "${pattern}")
    set(directive "${CMAKE_MATCH_0}")
    set(header "${CMAKE_MATCH_1}")
    list(FIND inlined_headers "${header}" seen)
    if(NOT seen EQUAL -1)
      string(REPLACE "${directive}" "/* ${header} already inlined */" text "${text}")
    else()
      if(NOT EXISTS "${GPUCOL_EMBED_ROOT}/${header}")
        message(FATAL_ERROR "${GPUCOL_EMBED_INPUT}: included header ${header} not found")
      endif()
      file(READ "${GPUCOL_EMBED_ROOT}/${header}" header_text)
      string(FIND "${text}" "${directive}" at)
      string(LENGTH "${directive}" directive_length)
      string(SUBSTRING "${text}" 0 ${at} before)
      math(EXPR after_start "${at} + ${directive_length}")
      string(SUBSTRING "${text}" ${after_start} -1 after)
      set(text "${before}/* begin ${header} */\n${header_text}\n/* end ${header} */${after}")
      list(APPEND inlined_headers "${header}")
    endif()
  endwhile()
  # <...> includes are left to the OpenCL preprocessor: shared headers put their host-only ones behind
  # #ifndef __OPENCL_VERSION__. A quoted include that is not a repository header cannot be resolved.
  if(text MATCHES "#[ \t]*include[ \t]*\"[^\"\n]*\"")
    message(FATAL_ERROR "${GPUCOL_EMBED_INPUT}: cannot inline ${CMAKE_MATCH_0}; quoted includes must be repository headers ending in .h")
  endif()
  if(text MATCHES "\\)gpucol_cl\"")
    message(FATAL_ERROR "${GPUCOL_EMBED_INPUT} contains the raw string delimiter )gpucol_cl\"")
  endif()
  # Some compilers limit the length of one string literal: emit pieces of at most 8000 characters, which
  # the compiler concatenates back (a raw string may be split anywhere).
  string(LENGTH "${text}" length)
  set(body "")
  set(at 0)
  while(at LESS length)
    string(SUBSTRING "${text}" ${at} 8000 piece)
    string(APPEND body "R\"gpucol_cl(${piece})gpucol_cl\"\n")
    math(EXPR at "${at} + 8000")
  endwhile()
  if(body STREQUAL "")
    set(body "\"\"\n")
  endif()
  set(depends "${GPUCOL_EMBED_OUTPUT}: ${GPUCOL_EMBED_INPUT}")
  foreach(header IN LISTS inlined_headers)
    string(APPEND depends " ${GPUCOL_EMBED_ROOT}/${header}")
  endforeach()
  file(WRITE "${GPUCOL_EMBED_OUTPUT}.d" "${depends}\n")
  file(WRITE "${GPUCOL_EMBED_OUTPUT}"
    "// Generated from ${GPUCOL_EMBED_INPUT} by cmake/GpucolEmbedKernels.cmake. Do not edit.\n"
    "namespace gpucol::opencl::kernels {\n"
    "extern const char* const ${GPUCOL_EMBED_NAME};\n"
    "const char* const ${GPUCOL_EMBED_NAME} =\n${body};\n"
    "}  // namespace gpucol::opencl::kernels\n")
  return()
endif()

set(GPUCOL_EMBED_SCRIPT "${CMAKE_CURRENT_LIST_FILE}")

# gpucol_embed_kernels(<out_sources_var> KERNELS <a.cl>... SHARED_HEADERS <h>...)
# Sets <out_sources_var> to the generated .cpp files and writes generated/gpucol_kernels/kernels.h, which
# declares one `const char* const <name>` per kernel file.
function(gpucol_embed_kernels out_var)
  cmake_parse_arguments(ARG "" "" "KERNELS;SHARED_HEADERS" ${ARGN})
  set(out_dir "${PROJECT_BINARY_DIR}/generated/gpucol_kernels")
  file(MAKE_DIRECTORY "${out_dir}")
  set(sources "")
  set(declarations "")
  foreach(kernel IN LISTS ARG_KERNELS)
    get_filename_component(name "${kernel}" NAME_WE)
    if(NOT name MATCHES "^[a-z][a-z0-9_]*$")
      message(FATAL_ERROR "kernel file name ${kernel} must be snake_case")
    endif()
    set(output "${out_dir}/${name}.cpp")
    add_custom_command(OUTPUT "${output}"
      COMMAND ${CMAKE_COMMAND} -DGPUCOL_EMBED_INPUT=${kernel} -DGPUCOL_EMBED_OUTPUT=${output}
              -DGPUCOL_EMBED_NAME=${name} -DGPUCOL_EMBED_ROOT=${PROJECT_SOURCE_DIR} -P ${GPUCOL_EMBED_SCRIPT}
      DEPENDS "${kernel}" ${ARG_SHARED_HEADERS} "${GPUCOL_EMBED_SCRIPT}"
      DEPFILE "${output}.d"
      COMMENT "Embedding OpenCL kernel ${name}.cl"
      VERBATIM)
    list(APPEND sources "${output}")
    string(APPEND declarations "/// Source of opencl/kernels/${name}.cl, shared headers inlined.\nextern const char* const ${name};\n")
  endforeach()
  set(header "// Generated by cmake/GpucolEmbedKernels.cmake. Do not edit.\n#pragma once\n\nnamespace gpucol::opencl::kernels {\n${declarations}}  // namespace gpucol::opencl::kernels\n")
  file(CONFIGURE OUTPUT "${out_dir}/kernels.h" CONTENT "${header}" @ONLY)
  set(${out_var} "${sources}" PARENT_SCOPE)
endfunction()
