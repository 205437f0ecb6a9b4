# cmake -D IN=/usr/include/ros/serialization.h -D OUT=<build>/ros_include/ros/serialization.h -P
# patch_serialization.cmake: upstream ros/roscpp_core#124 (C++20 removed
# std::allocator<T>::rebind), and the quoted includes of ros/ made <ros/...>.
file(READ "${IN}" text)
string(REPLACE "typename ContainerAllocator::template rebind<T>::other"
  "typename std::allocator_traits<ContainerAllocator>::template rebind_alloc<T>" text "${text}")
string(REPLACE "#include \"roscpp_serialization_macros.h\"" "#include <ros/roscpp_serialization_macros.h>"
  text "${text}")
string(REPLACE "#include \"serialized_message.h\"" "#include <ros/serialized_message.h>" text "${text}")
string(FIND "${text}" "::template rebind<" left)
if(NOT left EQUAL -1)
  message(FATAL_ERROR "patch_serialization.cmake: ${IN} still uses rebind<T>::other after the patch")
endif()
file(WRITE "${OUT}" "// Generated from ${IN} by examples/ros_bridge/patch_serialization.cmake.\n${text}")
