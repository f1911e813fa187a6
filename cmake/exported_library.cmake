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
