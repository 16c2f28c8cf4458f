# rovermap as a library: `cmake --install build --prefix P` installs the `rovermap` command, the
# static libraries, their headers, a CMake package (find_package(rovermap): rovermap::<module>)
# and a pkg-config file. Included from the top CMakeLists.txt once every module target exists.
#
#   P/bin/rovermap
#   P/lib/librovermap_<module>.a
#   P/include/rovermap/<module>/*.hpp     #include <rovermap/registration/Icp.hpp>
#   P/lib/cmake/rovermap/                 rovermapConfig.cmake, ...Version, rovermapTargets*.cmake
#   P/lib/pkgconfig/rovermap.pc
#   P/share/rovermap/default.yaml, presets/

include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# In link order: each module before the ones it uses (the pkg-config Libs line follows it).
set(ROVERMAP_LIBRARY_MODULES config campaign mosaic service mapper sim eval stereo io graph terrain dem registration)
set(rovermap_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/rovermap)

foreach(module IN LISTS ROVERMAP_LIBRARY_MODULES)
  set(target rovermap_${module})
  # Consumers see rovermap::<module>; in the tree the targets keep their rovermap_<module> names.
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${module})
  # The headers include each other repository-root style ("registration/Options.hpp"), so
  # include/rovermap must be on the consumer's path; include/ is there for the one supported
  # form, <rovermap/registration/Icp.hpp>, which cannot collide with a consumer's own config/,
  # io/ or sim/ folders.
  target_include_directories(${target} PUBLIC
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/rovermap>)
  # The headers are C++17 (std::optional, nested namespaces): say so to consumers.
  target_compile_features(${target} PUBLIC cxx_std_17)
  # io/detail/ holds parsing helpers of the .cpp files only.
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${module}/
    DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/rovermap/${module}
    FILES_MATCHING PATTERN "*.hpp" PATTERN "detail" EXCLUDE)
  list(APPEND rovermap_library_targets ${target})
  string(APPEND rovermap_pc_libs " -lrovermap_${module}")
endforeach()

# core/ is header-only (units, the stopwatch): headers of every module may include it.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/core/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/rovermap/core
  FILES_MATCHING PATTERN "*.hpp")

install(TARGETS rovermap RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The program behind every subcommand but a plain `register` (apps/Launcher.cpp finds it here).
install(TARGETS rovermap_full RUNTIME DESTINATION ${CMAKE_INSTALL_LIBEXECDIR}/rovermap)
install(TARGETS ${rovermap_library_targets} EXPORT rovermapTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(EXPORT rovermapTargets NAMESPACE rovermap:: DESTINATION ${rovermap_cmake_dir})

# The package config finds what the exported link interfaces name: static libraries carry their
# PRIVATE dependencies as $<LINK_ONLY:...>, so GDAL, yaml-cpp, OpenMP, GeographicLib and (with
# ROVERMAP_WITH_ROSBAG) RosbagStorage are the consumer's to find too. FindRosbagStorage.cmake
# goes beside it; GeographicLib's find module is where Debian puts it.
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/rovermapConfig.cmake.in
  ${PROJECT_BINARY_DIR}/rovermapConfig.cmake INSTALL_DESTINATION ${rovermap_cmake_dir})
# 0.x: a minor version may change the API.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/rovermapConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/rovermapConfig.cmake
  ${PROJECT_BINARY_DIR}/rovermapConfigVersion.cmake DESTINATION ${rovermap_cmake_dir})
if(ROVERMAP_WITH_ROSBAG)
  install(FILES ${PROJECT_SOURCE_DIR}/cmake/FindRosbagStorage.cmake
    DESTINATION ${rovermap_cmake_dir})
endif()

# pkg-config. Only static archives are installed, so a plain `pkg-config --libs rovermap` has to
# give the whole link line: the dependencies are in Requires and Libs, not in the .private
# fields (those only come with --static). Debian's rosbag_storage.pc requires pluginlib.pc,
# which Debian does not ship, so the bag libraries are listed by path instead, as
# FindRosbagStorage found them.
set(ROVERMAP_PC_LIBS "${rovermap_pc_libs}")
if(ROVERMAP_WITH_ROSBAG)
  list(JOIN RosbagStorage_LIBRARIES " " rovermap_pc_rosbag)
  string(APPEND ROVERMAP_PC_LIBS " ${rovermap_pc_rosbag}")
endif()
# The prefix is found from the .pc file's own folder, since `cmake --install --prefix P` picks
# it after configuration.
file(RELATIVE_PATH ROVERMAP_PC_PREFIX ${CMAKE_INSTALL_FULL_LIBDIR}/pkgconfig
  ${CMAKE_INSTALL_PREFIX})
string(REGEX REPLACE "/$" "" ROVERMAP_PC_PREFIX "${ROVERMAP_PC_PREFIX}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/rovermap.pc.in ${PROJECT_BINARY_DIR}/rovermap.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/rovermap.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# The configuration reference and presets (the command has the defaults compiled in).
install(FILES ${PROJECT_SOURCE_DIR}/config/default.yaml
  DESTINATION ${CMAKE_INSTALL_DATADIR}/rovermap)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/presets DESTINATION ${CMAKE_INSTALL_DATADIR}/rovermap)
