# Warnings, sanitizers and the helper that declares one library module.

add_library(hattr_compile_options INTERFACE)
target_compile_options(hattr_compile_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
  -Wno-missing-field-initializers -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual -Wimplicit-fallthrough
  $<$<BOOL:${HATTR_WERROR}>:-Werror>)

if(HATTR_SANITIZE)
  string(REPLACE ";" "," _hattr_san "${HATTR_SANITIZE}")
  target_compile_options(hattr_compile_options INTERFACE
    -fsanitize=${_hattr_san} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  target_link_options(hattr_compile_options INTERFACE -fsanitize=${_hattr_san})
  target_compile_definitions(hattr_compile_options INTERFACE HATTR_SANITIZED=1)
endif()


# hattr_add_module(NAME SOURCES ... DEPENDS ...): library target hattr_NAME, alias hattr::NAME.
function(hattr_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPENDS;PRIVATE_DEPENDS" ${ARGN})
  add_library(hattr_${name} ${ARG_SOURCES})
  add_library(hattr::${name} ALIAS hattr_${name})
  set_target_properties(hattr_${name} PROPERTIES EXPORT_NAME ${name} POSITION_INDEPENDENT_CODE ON)
  target_include_directories(hattr_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include>
    $<BUILD_INTERFACE:${PROJECT_BINARY_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(hattr_${name} PUBLIC ${ARG_DEPENDS} $<BUILD_INTERFACE:hattr_compile_options>
    PRIVATE ${ARG_PRIVATE_DEPENDS})
  install(TARGETS hattr_${name} EXPORT hattrTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
endfunction()

# hattr_add_plugin(NAME [INSTALL] SOURCES ... DEPENDS ...): a driver plugin, a shared object loaded
# with dlopen (plugin:/path/libNAME.so). Only the entry symbol is visible; the hattr code it
# links stays private to it (--exclude-libs), so it never clashes with the host's copy. INSTALL:
# a plugin hattr ships, built into the build folder's plugin folder (found as plugin:NAME, as
# under an installed prefix) and installed into PREFIX/LIBDIR/hattr/plugins.
function(hattr_add_plugin name)
  cmake_parse_arguments(ARG "INSTALL" "" "SOURCES;DEPENDS" ${ARGN})
  add_library(${name} MODULE ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE hattr::device ${ARG_DEPENDS} hattr_compile_options)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/plugins)
  set_target_properties(${name} PROPERTIES PREFIX "lib" CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
  target_link_options(${name} PRIVATE -Wl,--exclude-libs,ALL -Wl,--no-undefined)
  if(ARG_INSTALL)
    set_target_properties(${name} PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${HATTR_STAGED_PLUGIN_DIR})
    install(TARGETS ${name} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/hattr/plugins COMPONENT runtime)
  endif()
endfunction()
