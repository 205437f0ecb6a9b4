# endohaptics-ros-bridge and its ROS 1 stand-in (docs/ros.md): plain CMake against
# Debian 12's ROS 1 (roscpp 1.15), no catkin workspace. Only these programs and their tests use
# ROS; the library (include/endohaptics) has no ROS dependency.
#
# C++20: Debian's pre-generated message headers and ros/serialization.h use
# `Allocator::rebind<T>::other`, which C++20 removed (g++ 12 rejects it). At build time, into the
# build tree (never /usr): every message we use is generated again from its .msg with Debian's
# gencpp 0.7.0 (C++20-clean), and ros/serialization.h is copied with upstream ros/roscpp_core#124
# applied (std::allocator_traits<...>::rebind_alloc<T>). Both directories come before
# /usr/include.

find_package(roscpp REQUIRED)
find_program(ENDOHAPTICS_ROS_PYTHON python3 PATHS /usr/bin NO_DEFAULT_PATH)  # Debian's, not a venv's
find_file(ENDOHAPTICS_GENCPP gen_cpp.py PATHS /usr/lib/gencpp NO_DEFAULT_PATH)
find_path(ENDOHAPTICS_GENCPP_TEMPLATES msg.h.template PATHS /usr/share/gencpp NO_DEFAULT_PATH)
find_path(ENDOHAPTICS_ROS_SHARE std_msgs/msg/Header.msg PATHS /usr/share NO_DEFAULT_PATH)
find_file(ENDOHAPTICS_ROS_SERIALIZATION_H ros/serialization.h PATHS ${roscpp_INCLUDE_DIRS}
  /usr/include NO_DEFAULT_PATH)
foreach(v ENDOHAPTICS_ROS_PYTHON ENDOHAPTICS_GENCPP ENDOHAPTICS_GENCPP_TEMPLATES
          ENDOHAPTICS_ROS_SHARE ENDOHAPTICS_ROS_SERIALIZATION_H)
  if(NOT ${v})
    message(FATAL_ERROR "endohaptics: ENDOHAPTICS_BUILD_ROS needs Debian's ROS 1 packages "
      "(./run test installs them: python3-gencpp python3-genmsg libroscpp-dev ...): ${v} not found")
  endif()
endforeach()

set(ros_gen "${CMAKE_CURRENT_BINARY_DIR}/ros_include")
set(own_msgs "${CMAKE_CURRENT_LIST_DIR}/msg")
set(msg_paths -Istd_msgs:${ENDOHAPTICS_ROS_SHARE}/std_msgs/msg
  -Igeometry_msgs:${ENDOHAPTICS_ROS_SHARE}/geometry_msgs/msg
  -Isensor_msgs:${ENDOHAPTICS_ROS_SHARE}/sensor_msgs/msg
  -Iphantom_omni:${own_msgs}/phantom_omni -Itf2_msgs:${own_msgs}/tf2_msgs)
# package/Message: from Debian's .msg files, or from ours (msg/<package>/<Message>.msg).
set(ros_messages std_msgs/Header std_msgs/String std_msgs/MultiArrayDimension
  std_msgs/MultiArrayLayout std_msgs/Float64MultiArray geometry_msgs/Vector3 geometry_msgs/Point
  geometry_msgs/Quaternion geometry_msgs/Pose geometry_msgs/PoseStamped geometry_msgs/Wrench
  geometry_msgs/WrenchStamped geometry_msgs/Transform geometry_msgs/TransformStamped
  sensor_msgs/JointState phantom_omni/OmniFeedback tf2_msgs/TFMessage)
set(ros_headers)
foreach(m IN LISTS ros_messages)
  string(REPLACE "/" ";" parts "${m}")
  list(GET parts 0 package)
  list(GET parts 1 name)
  if(EXISTS "${own_msgs}/${package}/${name}.msg")
    set(source "${own_msgs}/${package}/${name}.msg")
  else()
    set(source "${ENDOHAPTICS_ROS_SHARE}/${package}/msg/${name}.msg")
  endif()
  set(header "${ros_gen}/${package}/${name}.h")
  add_custom_command(OUTPUT "${header}"
    COMMAND "${ENDOHAPTICS_ROS_PYTHON}" "${ENDOHAPTICS_GENCPP}" -p ${package} -o
      "${ros_gen}/${package}" -e "${ENDOHAPTICS_GENCPP_TEMPLATES}" ${msg_paths} "${source}"
    DEPENDS "${source}"
    COMMENT "gencpp: ${m}" VERBATIM)
  list(APPEND ros_headers "${header}")
endforeach()
# ros/serialization.h: rebind<T>::other -> allocator_traits rebind_alloc<T> (roscpp_core#124), and
# its quoted includes of its own directory made <ros/...> (the copy lives elsewhere).
add_custom_command(OUTPUT "${ros_gen}/ros/serialization.h"
  COMMAND "${CMAKE_COMMAND}" -D "IN=${ENDOHAPTICS_ROS_SERIALIZATION_H}"
    -D "OUT=${ros_gen}/ros/serialization.h" -P "${CMAKE_CURRENT_LIST_DIR}/patch_serialization.cmake"
  DEPENDS "${ENDOHAPTICS_ROS_SERIALIZATION_H}" "${CMAKE_CURRENT_LIST_DIR}/patch_serialization.cmake"
  COMMENT "roscpp_core#124: ros/serialization.h for C++20" VERBATIM)
list(APPEND ros_headers "${ros_gen}/ros/serialization.h")
add_custom_target(endohaptics_ros_messages DEPENDS ${ros_headers})

add_library(endohaptics_ros INTERFACE)
add_dependencies(endohaptics_ros endohaptics_ros_messages)
target_include_directories(endohaptics_ros SYSTEM BEFORE INTERFACE "${ros_gen}")
target_include_directories(endohaptics_ros SYSTEM INTERFACE ${roscpp_INCLUDE_DIRS})
target_link_libraries(endohaptics_ros INTERFACE ${roscpp_LIBRARIES})

target_sources(endohaptics_program_options PRIVATE ros_bridge/options.cpp
  ros_bridge/standin_options.cpp)
endohaptics_add_example(endohaptics-ros-bridge ros_bridge endohaptics::model_files
  endohaptics::secure_protocol endohaptics_ros)
add_executable(endohaptics-ros-touch-standin ros_bridge/touch_standin.cpp)
target_link_libraries(endohaptics-ros-touch-standin PRIVATE endohaptics_program_options
  endohaptics::endohaptics endohaptics_warnings fmt::fmt Threads::Threads endohaptics_ros)
# A stand-in for the Touch's driver (tests and docs/ros.md): a 1 kHz publisher with nothing to
# gain from -O3, which cost it 3 s of GCC's optimiser (15.8 -> 12.9 s of CPU at -O1).
target_compile_options(endohaptics-ros-touch-standin PRIVATE -O1)

if(ENDOHAPTICS_BUILD_TESTS)
  # Heap allocations of the loop thread while ROS traffic flows (tests/ros/ros_alloc_check.cpp).
  add_executable(endohaptics-ros-alloc-test "${PROJECT_SOURCE_DIR}/tests/ros/ros_alloc_check.cpp")
  target_include_directories(endohaptics-ros-alloc-test PRIVATE "${PROJECT_SOURCE_DIR}/tests"
    "${CMAKE_CURRENT_LIST_DIR}")
  target_link_libraries(endohaptics-ros-alloc-test PRIVATE endohaptics::endohaptics
    endohaptics_warnings fmt::fmt Threads::Threads endohaptics_ros)
  # End to end on ROS 1, each case with its own roscore on a free port (tests/ros/ros_e2e.py).
  foreach(case topics drop-in three-hosts alloc p99)
    add_test(NAME "ros: ${case}"
      COMMAND "${ENDOHAPTICS_ROS_PYTHON}" "${PROJECT_SOURCE_DIR}/tests/ros/ros_e2e.py"
        "$<TARGET_FILE_DIR:endohaptics-ros-bridge>" "${PROJECT_SOURCE_DIR}" ${case})
    # One ROS case at a time; `./run test` runs the quiet label with -j 2 by itself, so the rig
    # page's test (the other quiet one, mostly sleeping on 1 kHz loops) runs beside them.
    set_tests_properties("ros: ${case}" PROPERTIES LABELS "ros;quiet" TIMEOUT 90
      RESOURCE_LOCK endohaptics-ros PASS_REGULAR_EXPRESSION "PASS:" FAIL_REGULAR_EXPRESSION "FAIL:")
  endforeach()
endif()
