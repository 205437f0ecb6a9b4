# Fresh install of the build tree into PREFIX (run by CTest as a fixture setup).
file(REMOVE_RECURSE "${PREFIX}")
execute_process(COMMAND "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${PREFIX}"
  COMMAND_ERROR_IS_FATAL ANY)
if(NOT EXISTS "${PREFIX}/share/cmake/endohaptics/endohapticsConfig.cmake")
  message(FATAL_ERROR "install did not produce endohapticsConfig.cmake under ${PREFIX}")
endif()
