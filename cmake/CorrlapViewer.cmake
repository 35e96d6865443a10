# The script of the page `corrlap view` writes (viewer/README.md): three.js and viewer/src/ bundled
# by esbuild into one minified script, compiled into `target` as a byte array. The npm packages are
# installed into the build folder from viewer/package-lock.json (`npm ci` when configuring), so the
# versions are the pinned ones. Without node and npm, or when npm ci fails (offline), the library
# has no viewer (has_viewer() is false) and says so.
option(CORRLAP_VIEWER "bundle the HTML viewer's script (needs node and npm, and the npm registry once)" ON)

function(corrlap_add_viewer target)
  set(CORRLAP_HAVE_VIEWER OFF CACHE INTERNAL "the library embeds the viewer's script")
  if(NOT CORRLAP_VIEWER)
    message(STATUS "corrlap: HTML viewer off (CORRLAP_VIEWER=OFF)")
    return()
  endif()
  find_program(CORRLAP_NODE node)
  find_program(CORRLAP_NPM npm)
  if(NOT CORRLAP_NODE OR NOT CORRLAP_NPM)
    message(STATUS "corrlap: HTML viewer skipped: needs node and npm (Debian: nodejs npm; scripts/install_deps.sh "
                   "installs them)")
    return()
  endif()
  set(src ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/../viewer)
  set(out ${PROJECT_BINARY_DIR}/viewer)
  # npm ci at configure time, once per lock file: without the registry (offline) the build goes on
  # without the viewer instead of failing. node_modules/.package-lock.json is npm's own record.
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${src}/package.json ${src}/package-lock.json)
  file(SHA256 ${src}/package-lock.json lock_hash)
  if(NOT EXISTS ${out}/node_modules/.package-lock.json OR NOT "${CORRLAP_VIEWER_INSTALLED_LOCK}" STREQUAL "${lock_hash}")
    file(MAKE_DIRECTORY ${out})
    file(COPY ${src}/package.json ${src}/package-lock.json DESTINATION ${out})
    message(STATUS "corrlap: viewer: npm ci (three.js, esbuild, playwright-core) into ${out}")
    execute_process(COMMAND ${CORRLAP_NPM} ci --no-audit --no-fund --loglevel=error
                    WORKING_DIRECTORY ${out} RESULT_VARIABLE npm_result ERROR_VARIABLE npm_error OUTPUT_QUIET)
    if(NOT npm_result EQUAL 0)
      message(WARNING "corrlap: HTML viewer skipped: npm ci failed in ${out} (it needs the npm registry once; "
                      "reconfigure when online, or -DCORRLAP_VIEWER=OFF to stop trying):\n${npm_error}")
      return()
    endif()
    set(CORRLAP_VIEWER_INSTALLED_LOCK "${lock_hash}" CACHE INTERNAL "the package-lock.json installed into <build>/viewer")
  endif()
  set(CORRLAP_HAVE_VIEWER ON CACHE INTERNAL "the library embeds the viewer's script")
  file(GLOB page_sources CONFIGURE_DEPENDS ${src}/src/*.js)
  add_custom_command(
    OUTPUT ${out}/viewer.js
    COMMAND ${CMAKE_COMMAND} -E env NODE_PATH=${out}/node_modules ${out}/node_modules/.bin/esbuild ${src}/src/main.js
            --bundle --minify --format=iife --target=es2020 --log-level=warning --outfile=${out}/viewer.js
    DEPENDS ${src}/package-lock.json ${page_sources}
    COMMENT "viewer: bundling the page's script"
    VERBATIM)
  add_custom_command(
    OUTPUT ${out}/viewer_script.cpp
    COMMAND ${CORRLAP_NODE} ${src}/embed.mjs ${out}/viewer.js ${out}/viewer_script.cpp
    DEPENDS ${out}/viewer.js ${src}/embed.mjs
    COMMENT "viewer: embedding the script"
    VERBATIM)
  target_sources(${target} PRIVATE ${out}/viewer_script.cpp)
  target_compile_definitions(${target} PRIVATE CORRLAP_HAVE_VIEWER=1)
endfunction()
