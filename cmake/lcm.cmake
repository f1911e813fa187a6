# LCM 1.3.1 from Debian ships no CMake config (see shared/LCM.md): find it by hand.
find_path(LCM_INCLUDE_DIR lcm/lcm-cpp.hpp REQUIRED)
find_library(LCM_LIBRARY lcm REQUIRED)
find_program(LCM_GEN lcm-gen REQUIRED)
add_library(lcm::lcm UNKNOWN IMPORTED)
set_target_properties(lcm::lcm PROPERTIES
  IMPORTED_LOCATION "${LCM_LIBRARY}"
  INTERFACE_INCLUDE_DIRECTORIES "${LCM_INCLUDE_DIR}")
