# MODE=install (default): installs the build tree into WORK_DIR/prefix, checks that the installed
# headers include nothing but Eigen, the standard library and corrlap's own public headers, then
# configures, builds and runs the consumer against the installed package.
# MODE=build-tree: the same consumer against the build tree itself (corrlap_DIR=BUILD_DIR).
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
if(NOT MODE)
  set(MODE install)
endif()
if(MODE STREQUAL "install")
  execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix
    RESULT_VARIABLE rc OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "cmake --install failed (${rc})")
  endif()
  set(PREFIX ${WORK_DIR}/prefix)
  include(${CMAKE_CURRENT_LIST_DIR}/check_install_tree.cmake)
  set(package_hint -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix)
else()
  set(package_hint -Dcorrlap_DIR=${BUILD_DIR})
endif()
# CONSUMER_FLAGS: the sanitizer flags of a sanitizer build (empty otherwise); CONSUMER_CXX: the
# compiler of the build under test.
set(compiler_hint "")
if(CONSUMER_CXX)
  set(compiler_hint -DCMAKE_CXX_COMPILER=${CONSUMER_CXX})
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
  ${package_hint} ${compiler_hint} -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS=${CONSUMER_FLAGS}"
  "-DCMAKE_EXE_LINKER_FLAGS=${CONSUMER_FLAGS}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the consumer against the package (${MODE}) failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/build RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the consumer failed (${rc})")
endif()
execute_process(COMMAND ${WORK_DIR}/build/consumer RESULT_VARIABLE rc OUTPUT_VARIABLE out)
message(STATUS "consumer: ${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the consumer program failed (${rc})")
endif()
