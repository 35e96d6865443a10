# The script of the page `corrlap view` writes (viewer/README.md): three.js and viewer/src/ bundled
# by esbuild into one minified script, compiled into `target` as a byte array. The npm packages are
# installed into the build folder from viewer/package-lock.json (`npm ci`), so the versions are the
# pinned ones. Without node and npm the library has no viewer (has_viewer() is false) and says so.
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
  set(CORRLAP_HAVE_VIEWER ON CACHE INTERNAL "the library embeds the viewer's script")
  set(src ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/../viewer)
  set(out ${PROJECT_BINARY_DIR}/viewer)
  file(MAKE_DIRECTORY ${out})
  # node_modules/.package-lock.json is written by npm ci last: it stands for the whole install.
  add_custom_command(
    OUTPUT ${out}/node_modules/.package-lock.json
    COMMAND ${CMAKE_COMMAND} -E copy ${src}/package.json ${src}/package-lock.json ${out}
    COMMAND ${CORRLAP_NPM} ci --no-audit --no-fund --loglevel=error
    DEPENDS ${src}/package.json ${src}/package-lock.json
    WORKING_DIRECTORY ${out}
    COMMENT "viewer: npm ci (three.js, esbuild, playwright-core) into ${out}"
    VERBATIM)
  file(GLOB page_sources CONFIGURE_DEPENDS ${src}/src/*.js)
  add_custom_command(
    OUTPUT ${out}/viewer.js
    COMMAND ${CMAKE_COMMAND} -E env NODE_PATH=${out}/node_modules ${out}/node_modules/.bin/esbuild ${src}/src/main.js
            --bundle --minify --format=iife --target=es2020 --log-level=warning --outfile=${out}/viewer.js
    DEPENDS ${out}/node_modules/.package-lock.json ${page_sources}
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
