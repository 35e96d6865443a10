# Fails when a doctest case cannot be registered whole as one CTest test. doctest_discover_tests
# splits the list of names at ';' (a CMake list separator), so a name holding one becomes two CTest
# tests whose filters match nothing, and both pass without running the case.
# Usage: cmake -DTEST_BINARY=path/to/corrlap_tests -P check_test_names.cmake
execute_process(COMMAND "${TEST_BINARY}" --list-test-cases --no-version
                OUTPUT_VARIABLE listing RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${TEST_BINARY} --list-test-cases failed (${status})")
endif()
# Mark the separator first so that the names stay one list entry each.
string(REPLACE ";" "[;]" listing "${listing}")
string(REGEX MATCHALL "[^\n]*\\[;\\][^\n]*" bad "${listing}")
if(bad)
  list(JOIN bad "\n  " shown)
  message(FATAL_ERROR "test case names holding ';' (shown as [;]) are never run by ctest; use ',':\n  ${shown}")
endif()
