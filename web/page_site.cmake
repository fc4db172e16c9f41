# The page's part of the site (docs/web.md): index.html, css/, js/ and the three.js files it imports,
# copied from web/node_modules (npm ci in web/) into the site directory beside the WASM module.
# Target `web_page`; the site directory is ${PMSTREAM_WEB_DIR} (<build>/web, where target `web` puts the
# WASM module), so js/pmstream.js comes along with the page's own modules.
set(web_source ${CMAKE_CURRENT_LIST_DIR})
set(three_dir ${web_source}/node_modules/three)
if(NOT EXISTS ${three_dir}/build/three.module.js)
  message(STATUS "web/node_modules/three missing (npm ci in web/): the page is not assembled")
else()
file(GLOB page_files CONFIGURE_DEPENDS RELATIVE ${web_source} ${web_source}/index.html ${web_source}/css/*.css ${web_source}/js/*.js)
# three.module.js imports three.core.js beside it; the addons import 'three' through the page's import map.
set(vendor_files build/three.module.js build/three.core.js
    examples/jsm/controls/OrbitControls.js examples/jsm/controls/FlyControls.js)
set(page_outputs)
foreach(file ${page_files})
  add_custom_command(OUTPUT ${PMSTREAM_WEB_DIR}/${file}
                     COMMAND ${CMAKE_COMMAND} -E copy ${web_source}/${file} ${PMSTREAM_WEB_DIR}/${file}
                     DEPENDS ${web_source}/${file} VERBATIM)
  list(APPEND page_outputs ${PMSTREAM_WEB_DIR}/${file})
endforeach()
foreach(file ${vendor_files})
  string(REGEX REPLACE "^(build|examples/jsm)/" "" name ${file})
  if(file MATCHES "^examples/")
    set(name addons/${name})
  endif()
  add_custom_command(OUTPUT ${PMSTREAM_WEB_DIR}/vendor/${name}
                     COMMAND ${CMAKE_COMMAND} -E copy ${three_dir}/${file} ${PMSTREAM_WEB_DIR}/vendor/${name}
                     DEPENDS ${three_dir}/${file} VERBATIM)
  list(APPEND page_outputs ${PMSTREAM_WEB_DIR}/vendor/${name})
endforeach()
add_custom_target(web_page ALL DEPENDS ${page_outputs})
endif()
