# Small helpers shared by the CMakeLists of every folder.

function(corrlap_use_ccache)
  find_program(CCACHE_PROGRAM ccache)
  if(CCACHE_PROGRAM)
    set(CMAKE_CXX_COMPILER_LAUNCHER ${CCACHE_PROGRAM} PARENT_SCOPE)
    set(CMAKE_C_COMPILER_LAUNCHER ${CCACHE_PROGRAM} PARENT_SCOPE)
    message(STATUS "corrlap: using ccache ${CCACHE_PROGRAM}")
  endif()
endfunction()

# -Wall -Wextra on every target built from corrlap's own sources; with CORRLAP_WERROR (CI) they are
# errors. Dependencies come in through imported targets, whose headers are system includes, so
# their warnings never reach -Werror.
function(corrlap_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-deprecated-declarations)
  if(CORRLAP_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# corrlap_library(<folder-name> [PUBLIC deps...] [PRIVATE deps...] [EXCLUDE files...])
# One library per top-level folder: every .cpp below the folder belongs to it. Headers below the
# folder are installed with their sub-folders, except those in a detail/ folder: internal headers
# (TBB, intrinsics, assembly machinery) are never installed, so installed headers include Eigen and
# the standard library only (tests/install_tree_check.cmake verifies it). EXCLUDE: sources and headers
# (relative to the folder) left out, for an optional backend that is not configured.
function(corrlap_library name)
  cmake_parse_arguments(ARG "" "" "PUBLIC;PRIVATE;EXCLUDE" ${ARGN})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  file(GLOB_RECURSE headers CONFIGURE_DEPENDS RELATIVE ${CMAKE_CURRENT_SOURCE_DIR}
    ${CMAKE_CURRENT_SOURCE_DIR}/*.hpp ${CMAKE_CURRENT_SOURCE_DIR}/*.inc)
  foreach(excluded ${ARG_EXCLUDE})
    list(REMOVE_ITEM sources ${CMAKE_CURRENT_SOURCE_DIR}/${excluded})
    list(REMOVE_ITEM headers ${excluded})
  endforeach()
  add_library(corrlap_${name} ${sources})
  add_library(corrlap::${name} ALIAS corrlap_${name})
  set_target_properties(corrlap_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME corrlap_${name}
    VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR})
  target_include_directories(corrlap_${name} PUBLIC
    $<BUILD_INTERFACE:${CORRLAP_BUILD_INCLUDE_DIR}>
    $<INSTALL_INTERFACE:include>)
  target_link_libraries(corrlap_${name} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
  # The public headers are C++20: a consumer gets that requirement from the package (a compiler
  # whose default is older, e.g. clang-14's C++14, would fail on <optional>, <string_view>...).
  target_compile_features(corrlap_${name} PUBLIC cxx_std_20)
  corrlap_warnings(corrlap_${name})
  foreach(header ${headers})
    if(header MATCHES "(^|/)detail/")
      continue()
    endif()
    get_filename_component(subdir ${header} DIRECTORY)
    install(FILES ${CMAKE_CURRENT_SOURCE_DIR}/${header} DESTINATION include/corrlap/${name}/${subdir})
  endforeach()
  set_property(GLOBAL APPEND PROPERTY CORRLAP_EXPORTED_TARGETS corrlap_${name})
endfunction()
