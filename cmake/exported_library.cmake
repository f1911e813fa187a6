# SPDX-License-Identifier: Apache-2.0
# elaslam_exported_library(TARGET NAME): TARGET is a library other programs link
# (docs/embedding.md) as elaslam::NAME, the same name inside this tree (an alias, for
# projects that add_subdirectory(elaslam)) as installed (packaging/dev.cmake exports
# it). A static library's public headers are its folder's include/ in the build and
# <prefix>/include installed.
function(elaslam_exported_library target name)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  add_library(elaslam::${name} ALIAS ${target})
  get_target_property(type ${target} TYPE)
  if(NOT type STREQUAL "INTERFACE_LIBRARY")
    target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>)
  endif()
endfunction()

# elaslam_node_library(TARGET NAME PROGRAM SOURCES...): a node's library (no I/O)
# exported as elaslam::NAME, on the common layer and the message types (nlohmann_json,
# header-only, for its state file: inside the build only), and, with
# ELASLAM_BUILD_PROGRAMS, the node's program PROGRAM from the folder's main.cpp on the
# message layer.
function(elaslam_node_library target name program)
  add_library(${target} STATIC ${ARGN})
  elaslam_exported_library(${target} ${name})
  target_link_libraries(${target} PUBLIC elaslam_common elaslam_lcmtypes
                        PRIVATE $<BUILD_INTERFACE:nlohmann_json::nlohmann_json>)
  if(ELASLAM_BUILD_PROGRAMS)
    add_executable(${program} main.cpp)
    target_link_libraries(${program} PRIVATE ${target} elaslam_transport CLI11::CLI11)
  endif()
endfunction()

# elaslam_library(TARGET SOURCES...): a static library used inside this tree only, its
# public headers in its folder's include/.
function(elaslam_library target)
  add_library(${target} STATIC ${ARGN})
  target_include_directories(${target} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
endfunction()
