# SPDX-License-Identifier: Apache-2.0
# LCM: the library (cmake/lcm_library.cmake, shared with the installed config) and
# lcm-gen, which generates the message types at build time (lcmtypes/).
include(${CMAKE_CURRENT_LIST_DIR}/lcm_library.cmake)
find_program(LCM_GEN lcm-gen REQUIRED)
