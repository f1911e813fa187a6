# SPDX-License-Identifier: Apache-2.0
# lcm::lcm, LCM's C library and headers. LCM 1.3.1 from Debian ships no CMake config
# (see shared/LCM.md): found by hand. Used by the build (cmake/lcm.cmake) and by the
# installed elaslamConfig.cmake (the message types' headers include LCM's); a project
# that already has lcm::lcm (LCM's own config, 1.4 and later) keeps its own.
if(NOT TARGET lcm::lcm)
  find_path(LCM_INCLUDE_DIR lcm/lcm-cpp.hpp)
  find_library(LCM_LIBRARY lcm)
  if(NOT LCM_INCLUDE_DIR OR NOT LCM_LIBRARY)
    message(FATAL_ERROR "elaslam: LCM not found (header lcm/lcm-cpp.hpp: '${LCM_INCLUDE_DIR}', "
                        "library liblcm: '${LCM_LIBRARY}'); Debian: apt-get install liblcm-dev")
  endif()
  add_library(lcm::lcm UNKNOWN IMPORTED)
  set_target_properties(lcm::lcm PROPERTIES
    IMPORTED_LOCATION "${LCM_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${LCM_INCLUDE_DIR}")
endif()
