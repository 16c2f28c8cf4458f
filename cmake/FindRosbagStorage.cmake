# FindRosbagStorage: ROS 1 rosbag_storage and the message headers rovermap reads bags with, as
# Debian 12 packages them (librosbag-storage-dev, libsensor-msgs-dev, libnav-msgs-dev,
# libgeometry-msgs-dev, libtf2-msgs-dev).
#
# Debian's rosbag_storageConfig.cmake is catkin's and its pkg-config file names only the top
# include directory, while rosbag/bag.h includes <pluginlib/class_loader.hpp>, which Debian
# installs one level down (include/pluginlib/pluginlib/...), as it does class_loader, rcpputils,
# rcutils and ament_index_cpp (ROS 2 layout), all of which pluginlib's headers include. Each of those folders is found here by a header it holds.
#
# Defines RosbagStorage_FOUND, RosbagStorage_INCLUDE_DIRS, RosbagStorage_LIBRARIES and the
# imported target RosbagStorage::RosbagStorage.

include(FindPackageHandleStandardArgs)

find_path(RosbagStorage_INCLUDE_DIR rosbag/bag.h)
find_path(RosbagStorage_ROS_INCLUDE_DIR ros/time.h)
find_path(RosbagStorage_CONSOLE_BRIDGE_INCLUDE_DIR console_bridge/console.h)
find_path(RosbagStorage_PLUGINLIB_INCLUDE_DIR pluginlib/class_loader.hpp PATH_SUFFIXES pluginlib)
find_path(RosbagStorage_CLASS_LOADER_INCLUDE_DIR class_loader/class_loader.hpp
  PATH_SUFFIXES class_loader)
find_path(RosbagStorage_RCPPUTILS_INCLUDE_DIR rcpputils/shared_library.hpp PATH_SUFFIXES rcpputils)
find_path(RosbagStorage_RCUTILS_INCLUDE_DIR rcutils/types.h PATH_SUFFIXES rcutils)
find_path(RosbagStorage_AMENT_INDEX_INCLUDE_DIR ament_index_cpp/get_resource.hpp
  PATH_SUFFIXES ament_index_cpp)
find_path(RosbagStorage_TINYXML2_INCLUDE_DIR tinyxml2.h)
# Message headers (header-only packages).
find_path(RosbagStorage_MSGS_INCLUDE_DIR sensor_msgs/Image.h)
find_path(RosbagStorage_NAV_MSGS_INCLUDE_DIR nav_msgs/Odometry.h)
find_path(RosbagStorage_GEOMETRY_MSGS_INCLUDE_DIR geometry_msgs/TransformStamped.h)
find_path(RosbagStorage_TF2_MSGS_INCLUDE_DIR tf2_msgs/TFMessage.h)

find_library(RosbagStorage_LIBRARY rosbag_storage)
find_library(RosbagStorage_ROSTIME_LIBRARY rostime)
find_library(RosbagStorage_SERIALIZATION_LIBRARY roscpp_serialization)
find_library(RosbagStorage_CPP_COMMON_LIBRARY cpp_common)
find_library(RosbagStorage_CONSOLE_BRIDGE_LIBRARY console_bridge)
find_library(RosbagStorage_CLASS_LOADER_LIBRARY class_loader)
find_library(RosbagStorage_RCPPUTILS_LIBRARY rcpputils)
find_library(RosbagStorage_RCUTILS_LIBRARY rcutils)
find_library(RosbagStorage_AMENT_INDEX_LIBRARY ament_index_cpp)
find_library(RosbagStorage_ROSLIB_LIBRARY roslib)
find_library(RosbagStorage_TINYXML2_LIBRARY tinyxml2)
find_library(RosbagStorage_BOOST_FILESYSTEM_LIBRARY boost_filesystem)

set(_rosbag_storage_include_vars
  RosbagStorage_INCLUDE_DIR RosbagStorage_ROS_INCLUDE_DIR
  RosbagStorage_CONSOLE_BRIDGE_INCLUDE_DIR RosbagStorage_PLUGINLIB_INCLUDE_DIR
  RosbagStorage_CLASS_LOADER_INCLUDE_DIR RosbagStorage_RCPPUTILS_INCLUDE_DIR
  RosbagStorage_RCUTILS_INCLUDE_DIR RosbagStorage_AMENT_INDEX_INCLUDE_DIR
  RosbagStorage_TINYXML2_INCLUDE_DIR RosbagStorage_MSGS_INCLUDE_DIR
  RosbagStorage_NAV_MSGS_INCLUDE_DIR RosbagStorage_GEOMETRY_MSGS_INCLUDE_DIR
  RosbagStorage_TF2_MSGS_INCLUDE_DIR)
set(_rosbag_storage_library_vars
  RosbagStorage_LIBRARY RosbagStorage_ROSTIME_LIBRARY RosbagStorage_SERIALIZATION_LIBRARY
  RosbagStorage_CPP_COMMON_LIBRARY RosbagStorage_CONSOLE_BRIDGE_LIBRARY
  RosbagStorage_CLASS_LOADER_LIBRARY RosbagStorage_RCPPUTILS_LIBRARY
  RosbagStorage_RCUTILS_LIBRARY RosbagStorage_AMENT_INDEX_LIBRARY RosbagStorage_ROSLIB_LIBRARY
  RosbagStorage_TINYXML2_LIBRARY RosbagStorage_BOOST_FILESYSTEM_LIBRARY)

find_package_handle_standard_args(RosbagStorage
  REQUIRED_VARS ${_rosbag_storage_library_vars} ${_rosbag_storage_include_vars})

if(RosbagStorage_FOUND)
  set(RosbagStorage_INCLUDE_DIRS)
  foreach(_var IN LISTS _rosbag_storage_include_vars)
    list(APPEND RosbagStorage_INCLUDE_DIRS "${${_var}}")
  endforeach()
  list(REMOVE_DUPLICATES RosbagStorage_INCLUDE_DIRS)
  set(RosbagStorage_LIBRARIES)
  foreach(_var IN LISTS _rosbag_storage_library_vars)
    list(APPEND RosbagStorage_LIBRARIES "${${_var}}")
  endforeach()
  if(NOT TARGET RosbagStorage::RosbagStorage)
    add_library(RosbagStorage::RosbagStorage INTERFACE IMPORTED)
    # Imported, so its include folders are SYSTEM ones: our warning flags spare the ROS headers.
    set_target_properties(RosbagStorage::RosbagStorage PROPERTIES
      INTERFACE_INCLUDE_DIRECTORIES "${RosbagStorage_INCLUDE_DIRS}"
      INTERFACE_LINK_LIBRARIES "${RosbagStorage_LIBRARIES}")
  endif()
endif()

mark_as_advanced(${_rosbag_storage_include_vars} ${_rosbag_storage_library_vars})
unset(_rosbag_storage_include_vars)
unset(_rosbag_storage_library_vars)
