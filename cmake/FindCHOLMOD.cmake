# FindCHOLMOD
# -----------
# Finds CHOLMOD from SuiteSparse. Debian's SuiteSparse 5.x ships no CMake package, so we look
# for the header and the libraries ourselves.
#
# Result: CHOLMOD_FOUND, CHOLMOD_INCLUDE_DIR, CHOLMOD_LIBRARIES, imported target CHOLMOD::CHOLMOD.

find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig)
foreach(lib amd camd colamd ccolamd)
  string(TOUPPER ${lib} LIB)
  find_library(${LIB}_LIBRARY ${lib})
endforeach()
find_library(METIS_LIBRARY metis)

if(CHOLMOD_INCLUDE_DIR AND EXISTS "${CHOLMOD_INCLUDE_DIR}/cholmod_core.h")
  file(STRINGS "${CHOLMOD_INCLUDE_DIR}/cholmod_core.h" _ver REGEX "#define CHOLMOD_(MAIN|SUB|SUBSUB)_VERSION")
  string(REGEX REPLACE ".*MAIN_VERSION +([0-9]+).*" "\\1" _maj "${_ver}")
  string(REGEX REPLACE ".*CHOLMOD_SUB_VERSION +([0-9]+).*" "\\1" _min "${_ver}")
  string(REGEX REPLACE ".*SUBSUB_VERSION +([0-9]+).*" "\\1" _pat "${_ver}")
  set(CHOLMOD_VERSION "${_maj}.${_min}.${_pat}")
endif()

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CHOLMOD
  REQUIRED_VARS CHOLMOD_LIBRARY CHOLMOD_INCLUDE_DIR SUITESPARSE_CONFIG_LIBRARY AMD_LIBRARY COLAMD_LIBRARY
  VERSION_VAR CHOLMOD_VERSION
  REASON_FAILURE_MESSAGE "install the Debian package libsuitesparse-dev")

if(CHOLMOD_FOUND)
  set(CHOLMOD_LIBRARIES ${CHOLMOD_LIBRARY} ${AMD_LIBRARY} ${CAMD_LIBRARY} ${COLAMD_LIBRARY}
      ${CCOLAMD_LIBRARY} ${SUITESPARSE_CONFIG_LIBRARY})
  if(METIS_LIBRARY)
    list(APPEND CHOLMOD_LIBRARIES ${METIS_LIBRARY})
  endif()
  if(NOT TARGET CHOLMOD::CHOLMOD)
    add_library(CHOLMOD::CHOLMOD INTERFACE IMPORTED)
    set_target_properties(CHOLMOD::CHOLMOD PROPERTIES
      INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
      INTERFACE_LINK_LIBRARIES "${CHOLMOD_LIBRARIES}")
  endif()
endif()
mark_as_advanced(CHOLMOD_INCLUDE_DIR CHOLMOD_LIBRARY SUITESPARSE_CONFIG_LIBRARY METIS_LIBRARY)
