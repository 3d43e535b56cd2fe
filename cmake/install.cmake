# `cmake --install`: the layer libraries, their headers, the robot files and
# the shipped scenes, and a CMake package, so that another project can write
#
#   find_package(pumasim REQUIRED)
#   target_link_libraries(app PRIVATE pumasim::pumasim)
#
# (examples/consumer/ does; the test Package.InstallAndConsume builds it
# against an installed copy). Included by the top-level CMakeLists.txt after
# the layers are defined. Layout under the prefix:
#
#   include/pumasim/models/..., integrators/..., simulation/...
#                              the repository's own include paths, kept
#   lib/libpumasim_*.a         the layers (static, as built here)
#   lib/cmake/pumasim/         pumasim-config.cmake, -config-version.cmake, -targets*.cmake
#   share/pumasim/robots/      models/robots/ (puma560.toml and its sources, stanford.toml, planar2.toml)
#   share/pumasim/scenes/      experiments/scenes/
#
# Nothing here changes how the build tree's own targets are compiled: what the
# installed targets add for their consumers is wrapped in $<INSTALL_INTERFACE:>.
include(CMakePackageConfigHelpers)

# The layers, lowest first, exported as pumasim::<name>; pumasim::models is
# the five model layers, pumasim::pumasim everything (the simulation layer and
# all below it). The in-tree ALIASes let a parent project use the same names
# after add_subdirectory().
set(_pumasim_exported
  pumasim_core:core pumasim_dynamics:dynamics pumasim_robot:robot pumasim_reference:reference pumasim_plant:plant
  pumasim_scene:scene pumasim_models:models pumasim_integrators:integrators pumasim_simulation:simulation)
add_library(pumasim_package INTERFACE)
target_link_libraries(pumasim_package INTERFACE pumasim_simulation)
list(APPEND _pumasim_exported pumasim_package:pumasim)
set(_pumasim_targets "")
foreach(_pair IN LISTS _pumasim_exported)
  string(REPLACE ":" ";" _pair "${_pair}")
  list(GET _pair 0 _target)
  list(GET _pair 1 _name)
  set_target_properties(${_target} PROPERTIES EXPORT_NAME ${_name})
  add_library(pumasim::${_name} ALIAS ${_target})
  list(APPEND _pumasim_targets ${_target})
endforeach()

# ABI. The libraries are compiled with ${PUMASIM_NATIVE_FLAG} (-march=native
# when PUMASIM_NATIVE is ON), which changes Eigen's alignment of fixed-size
# objects (32 bytes with AVX against 16 without): a consumer compiled without
# it passes differently aligned objects across the boundary ("double free or
# corruption"). So the installed targets carry the flag in their interface;
# every exported target links one of these two. C++20 likewise: the headers
# use it. In the build tree both are set for every target already.
if(PUMASIM_NATIVE_FLAG)
  target_compile_options(pumasim_dynamics INTERFACE $<INSTALL_INTERFACE:${PUMASIM_NATIVE_FLAG}>)
  target_compile_options(pumasim_integrators INTERFACE $<INSTALL_INTERFACE:${PUMASIM_NATIVE_FLAG}>)
endif()
target_compile_features(pumasim_dynamics INTERFACE $<INSTALL_INTERFACE:cxx_std_20>)
target_compile_features(pumasim_integrators INTERFACE $<INSTALL_INTERFACE:cxx_std_20>)

set(PUMASIM_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/pumasim)
set(PUMASIM_INSTALL_DATADIR ${CMAKE_INSTALL_DATADIR}/pumasim)

install(TARGETS ${_pumasim_targets} EXPORT pumasim-targets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# Headers, in the repository's layout under include/pumasim. Left out: the
# files that include SUNDIALS and Boost's uBLAS (implementation details of
# the integrators' .cpp files; DESIGN.md keeps SUNDIALS behind one wall) and
# the test set, which is not part of the package.
foreach(_dir core models/dynamics models/robot models/reference models/plant models/scene integrators
             simulation)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${_dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/pumasim/${_dir}
    FILES_MATCHING PATTERN "*.hpp"
    PATTERN "testset" EXCLUDE
    PATTERN "sundials_common.hpp" EXCLUDE
    PATTERN "sundials_dense_lu.hpp" EXCLUDE
    PATTERN "rosenbrock_coefficients.hpp" EXCLUDE)
endforeach()

# Data: the robot files (with their sources) and the shipped scenes. A scene
# names its robot ("puma560"), which load_robot looks up in $PUMASIM_ROBOTS_DIR,
# else in the source tree the library was built from: a consumer of an
# installed copy sets PUMASIM_ROBOTS_DIR to ${pumasim_ROBOTS_DIR}.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/models/robots/ DESTINATION ${PUMASIM_INSTALL_DATADIR}/robots)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/experiments/scenes/ DESTINATION ${PUMASIM_INSTALL_DATADIR}/scenes)

install(EXPORT pumasim-targets NAMESPACE pumasim:: DESTINATION ${PUMASIM_INSTALL_CMAKEDIR})

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/pumasim-config.cmake.in
  ${PROJECT_BINARY_DIR}/pumasim-config.cmake
  INSTALL_DESTINATION ${PUMASIM_INSTALL_CMAKEDIR}
  PATH_VARS PUMASIM_INSTALL_DATADIR)
# 0.x: a minor version may change the interface.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/pumasim-config-version.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/pumasim-config.cmake ${PROJECT_BINARY_DIR}/pumasim-config-version.cmake
  DESTINATION ${PUMASIM_INSTALL_CMAKEDIR})
