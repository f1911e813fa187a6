# SPDX-License-Identifier: Apache-2.0
# ---- dev: the libraries, to embed elaslam in one's own program (docs/embedding.md) ----
# component dev, package elaslam-dev:
#   <libdir>/libelaslam_{common,transport,robot,main}.a     static, as the programs use them
#   include/elaslam/{common,transport,robot_node,main_robot}/*.hpp  their public headers
#   include/elaslam/<type>.hpp                              the generated LCM C++ message types
#   <libdir>/cmake/elaslam/elaslam{Config,ConfigVersion,Targets*}.cmake, lcm_library.cmake
#                                                           find_package(elaslam CONFIG)
#   <libdir>/pkgconfig/elaslam.pc                           pkg-config (written at install
#                                                           time: the prefix is known then)
# The targets, elaslam::<name> (the same names under add_subdirectory / FetchContent):
#   lcmtypes   the generated message types (header-only; LCM's headers and library)
#   common     config loading, geometry, contract bounds, stats (Eigen, yaml-cpp, libsodium)
#   transport  the Transport interface, LCM and in-process transports, node shell, keys
#   robot      one robot's filter: EkfSlam, ElaGate, LMap, Robot, RobotNode (no I/O)
#   main       the main robot's global map and node (no I/O but its state file)
# Not exported: team, simulator, dataset, viewer (the programs' internals; they change
# with the experiments). Nothing here is rebuilt by `cmake --install`.
include(CMakePackageConfigHelpers)
set(ELASLAM_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/elaslam)
set(ELASLAM_EXPORTED elaslam_lcmtypes elaslam_common elaslam_transport elaslam_robot elaslam_main)
install(TARGETS ${ELASLAM_EXPORTED} EXPORT elaslamTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT elaslamTargets NAMESPACE elaslam:: DESTINATION ${ELASLAM_CMAKEDIR} COMPONENT dev)
foreach(d common transport robot_node main_robot)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${d}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
          COMPONENT dev FILES_MATCHING PATTERN "*.hpp")
endforeach()
# Generated at build time (lcmtypes/CMakeLists.txt); the public headers include them.
install(DIRECTORY ${PROJECT_BINARY_DIR}/lcmgen/cpp/elaslam DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        COMPONENT dev FILES_MATCHING PATTERN "*.hpp")

configure_package_config_file(${CMAKE_CURRENT_SOURCE_DIR}/dev/elaslamConfig.cmake.in
                              ${CMAKE_CURRENT_BINARY_DIR}/dev/elaslamConfig.cmake
                              INSTALL_DESTINATION ${ELASLAM_CMAKEDIR} NO_SET_AND_CHECK_MACRO)
# 0.x: a new minor version may change the API (SameMinorVersion).
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/dev/elaslamConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/dev/elaslamConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/dev/elaslamConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/lcm_library.cmake
        DESTINATION ${ELASLAM_CMAKEDIR} COMPONENT dev)
install(CODE "${ELASLAM_INSTALL_PRELUDE}
elaslam_install_pc(\"${ELASLAM_INSTALL_WORK}\" \"${CMAKE_CURRENT_SOURCE_DIR}/dev/elaslam.pc.in\")"
        COMPONENT dev)
