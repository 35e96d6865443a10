# Small helpers shared by the CMakeLists of every folder.

function(corrlap_use_ccache)
  find_program(CCACHE_PROGRAM ccache)
  if(CCACHE_PROGRAM)
    set(CMAKE_CXX_COMPILER_LAUNCHER ${CCACHE_PROGRAM} PARENT_SCOPE)
    set(CMAKE_C_COMPILER_LAUNCHER ${CCACHE_PROGRAM} PARENT_SCOPE)
    message(STATUS "corrlap: using ccache ${CCACHE_PROGRAM}")
  endif()
endfunction()

function(corrlap_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-deprecated-declarations)
endfunction()

# corrlap_library(<folder-name> [PUBLIC deps...] [PRIVATE deps...])
# One library per top-level folder; every .cpp in the folder belongs to it, every .hpp is installed.
function(corrlap_library name)
  cmake_parse_arguments(ARG "" "" "PUBLIC;PRIVATE" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  file(GLOB headers CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.hpp)
  add_library(corrlap_${name} ${sources} ${headers})
  add_library(corrlap::${name} ALIAS corrlap_${name})
  set_target_properties(corrlap_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME corrlap_${name}
    VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR})
  target_include_directories(corrlap_${name} PUBLIC
    $<BUILD_INTERFACE:${CORRLAP_BUILD_INCLUDE_DIR}>
    $<INSTALL_INTERFACE:include>)
  target_link_libraries(corrlap_${name} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
  corrlap_warnings(corrlap_${name})
  install(FILES ${headers} DESTINATION include/corrlap/${name})
  set_property(GLOBAL APPEND PROPERTY CORRLAP_EXPORTED_TARGETS corrlap_${name})
endfunction()
