# Protocol v2 checks that need the programs (included by examples/CMakeLists.txt with tests on):
# the test vectors of docs/protocol.md against Python's hashlib.blake2b, and the attack suite
# against endohaptics-bridge and endohaptics-sbrio-emulator on 127.0.0.1 (tests/e2e/attack_v2.py).
add_executable(endohaptics-v2-vectors "${PROJECT_SOURCE_DIR}/tests/protocol/v2_vectors.cpp")
target_link_libraries(endohaptics-v2-vectors PRIVATE endohaptics::secure_protocol
  endohaptics_warnings)
find_package(Python3 COMPONENTS Interpreter)
if(NOT Python3_Interpreter_FOUND)
  message(WARNING "endohaptics: python3 not found: the v2 vector check and attack suite are not run")
  return()
endif()
add_test(NAME "protocol v2: test vectors agree with hashlib.blake2b"
  COMMAND "${Python3_EXECUTABLE}" "${PROJECT_SOURCE_DIR}/tests/protocol/v2_vectors_check.py"
    "$<TARGET_FILE:endohaptics-v2-vectors>" "${PROJECT_SOURCE_DIR}/docs/protocol.md")
set_tests_properties("protocol v2: test vectors agree with hashlib.blake2b" PROPERTIES
  LABELS protocol TIMEOUT 30 PASS_REGULAR_EXPRESSION "PASS:" FAIL_REGULAR_EXPRESSION "FAIL:")
# The check can fail: the same page with one bit of the first tag flipped is refused.
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${PROJECT_SOURCE_DIR}/docs/protocol.md")
file(READ "${PROJECT_SOURCE_DIR}/docs/protocol.md" protocol_md)
string(REPLACE "99a104f195feff0031c95c4c4d52d19a" "99a104f195feff0031c95c4c4d52d19b" protocol_md
  "${protocol_md}")
file(WRITE "${CMAKE_CURRENT_BINARY_DIR}/protocol_one_bit_flipped.md" "${protocol_md}")
add_test(NAME "protocol v2: the vector check refuses a page with one tag bit flipped"
  COMMAND "${Python3_EXECUTABLE}" "${PROJECT_SOURCE_DIR}/tests/protocol/v2_vectors_check.py"
    "$<TARGET_FILE:endohaptics-v2-vectors>" "${CMAKE_CURRENT_BINARY_DIR}/protocol_one_bit_flipped.md")
set_tests_properties("protocol v2: the vector check refuses a page with one tag bit flipped"
  PROPERTIES LABELS protocol TIMEOUT 30
  PASS_REGULAR_EXPRESSION "FAIL: docs/protocol.md does not show vector hello")

# Key files and --protocol on the command line (tests/e2e/cli_strict.sh, scenario keys).
add_test(NAME "e2e: strict command lines, keys"
  COMMAND bash "${PROJECT_SOURCE_DIR}/tests/e2e/cli_strict.sh" "$<TARGET_FILE_DIR:endohaptics-bridge>" keys)
set_tests_properties("e2e: strict command lines, keys" PROPERTIES LABELS e2e TIMEOUT 60
  PASS_REGULAR_EXPRESSION "PASS:")

# The attack suite: one CTest entry per case, each a few seconds (timing-sensitive: run alone).
foreach(case no-key bit-flips truncations replay reorder held-back stale-session
             replay-after-stop relay-restart cross-rig flood-sbrio flood-pc pinned-2016)
  add_test(NAME "attack v2: ${case}"
    COMMAND "${Python3_EXECUTABLE}" "${PROJECT_SOURCE_DIR}/tests/e2e/attack_v2.py"
      "$<TARGET_FILE_DIR:endohaptics-bridge>" ${case})
  set_tests_properties("attack v2: ${case}" PROPERTIES LABELS attack TIMEOUT 60 RUN_SERIAL TRUE
    PASS_REGULAR_EXPRESSION "PASS:" FAIL_REGULAR_EXPRESSION "FAIL:")
endforeach()
