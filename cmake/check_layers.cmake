# Layer check (docs/architecture.md, "Layers"): every header of include/endohaptics/<area>/ may
# include only headers of its own area and of the areas listed for it below, and no header of the
# real-time core may include an offline library (JSON, option parsing, file streams).
# Usage: cmake -DINCLUDE_DIR=<dir containing endohaptics/> -P check_layers.cmake
# Exits non-zero naming every violation (file:line, the include, what the area may include).

cmake_minimum_required(VERSION 3.25)

# The layer picture: area -> the areas it may include (besides itself).
set(allowed_core "")
set(allowed_protocol core)
set(allowed_model core)
set(allowed_kinematics core protocol)
set(allowed_estimation core protocol model)
set(allowed_transport core protocol)
set(allowed_teleop core protocol model kinematics estimation transport)
set(allowed_sim core protocol model kinematics estimation transport teleop)
set(allowed_identification core model)
set(allowed_files core protocol model kinematics estimation transport teleop sim identification)
set(allowed_workflow core protocol model kinematics estimation teleop sim identification files)
# Headers held below their area's layer: header -> the only areas it may include (its own area
# is not implied: another header of the area could reach further).
# files/model_file.hpp reads and writes model/ and estimation/ types only (a joint model's
# parameters are the estimation type, written through its field list: files/parameter_json.hpp),
# so that a program that loads a model (the bridge, through files/bridge_config.hpp) does not
# compile identification; the conversions from identification results are in
# files/identified_model_file.hpp. An entry with a slash names one header (files/json_text.hpp:
# the bounded JSON reading, itself only core; files/parameter_json.hpp, core and json_text).
# <area>/impl/<name>.ipp (an offline header's function bodies, or the explicit instantiations of
# the core's numerics: core/separate_compilation.hpp) are checked like headers of the area;
# model_file's include only model_file.hpp.
set(restricted_headers "files/model_file.hpp" "files/impl/model_file.ipp"
  "files/parameter_json.hpp")
set(allowed_header_files/parameter_json.hpp core files/json_text.hpp)
set(allowed_header_files/model_file.hpp core model estimation files/json_text.hpp
  files/parameter_json.hpp files/impl/model_file.ipp)
set(allowed_header_files/impl/model_file.ipp files/model_file.hpp)
# The real-time core: never reaches an offline header or library.
set(realtime_areas core protocol model kinematics estimation transport teleop)
set(offline_libraries "nlohmann/" "CLI/" "fmt/" "toml++/" "fstream" "iostream" "sstream")

if(NOT INCLUDE_DIR)
  message(FATAL_ERROR "check_layers.cmake: pass -DINCLUDE_DIR=<directory holding endohaptics/>")
endif()
file(GLOB_RECURSE headers RELATIVE "${INCLUDE_DIR}/endohaptics" "${INCLUDE_DIR}/endohaptics/*.hpp"
  "${INCLUDE_DIR}/endohaptics/*.ipp")
if(NOT headers)
  message(FATAL_ERROR "check_layers.cmake: no headers under ${INCLUDE_DIR}/endohaptics")
endif()
set(violations 0)
set(checked 0)
foreach(header IN LISTS headers)
  if(NOT header MATCHES "^([a-z_]+)/")
    continue()  # the umbrella header endohaptics.hpp includes everything by design
  endif()
  set(area "${CMAKE_MATCH_1}")
  set(allowed ${area} ${allowed_${area}})
  set(rule "area '${area}'")
  if(header IN_LIST restricted_headers)
    set(allowed ${allowed_header_${header}})
    set(rule "${header} (held below its area)")
  endif()
  if(NOT DEFINED allowed_${area})
    message(SEND_ERROR "${header}: area '${area}' is not in the layer picture of check_layers.cmake")
    math(EXPR violations "${violations} + 1")
    continue()
  endif()
  file(STRINGS "${INCLUDE_DIR}/endohaptics/${header}" lines)
  set(line_number 0)
  foreach(line IN LISTS lines)
    math(EXPR line_number "${line_number} + 1")
    if(NOT line MATCHES "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"]")
      continue()
    endif()
    set(target "${CMAKE_MATCH_1}")
    math(EXPR checked "${checked} + 1")
    if(target MATCHES "^endohaptics/([a-z_]+)/(.*)$")
      set(to "${CMAKE_MATCH_1}")
      set(to_header "${CMAKE_MATCH_1}/${CMAKE_MATCH_2}")
      if(NOT to IN_LIST allowed AND NOT to_header IN_LIST allowed)
        list(JOIN allowed " " allowed_text)
        message(SEND_ERROR "${header}:${line_number}: includes ${target}: ${rule} may "
          "include only: ${allowed_text}")
        math(EXPR violations "${violations} + 1")
      endif()
    elseif(target MATCHES "^endohaptics/")
      message(SEND_ERROR "${header}:${line_number}: includes ${target} (the umbrella header)")
      math(EXPR violations "${violations} + 1")
    elseif(area IN_LIST realtime_areas)
      foreach(lib IN LISTS offline_libraries)
        string(FIND "${target}" "${lib}" at)
        if(at EQUAL 0)
          message(SEND_ERROR "${header}:${line_number}: includes <${target}>: the real-time "
            "core (${realtime_areas}) never includes an offline library")
          math(EXPR violations "${violations} + 1")
        endif()
      endforeach()
    endif()
  endforeach()
endforeach()
list(LENGTH headers count)
if(violations GREATER 0)
  message(FATAL_ERROR "layer check: ${violations} violation(s) in ${count} headers")
endif()
message(STATUS "layer check: ${count} headers, ${checked} includes, every one inside its layer")
