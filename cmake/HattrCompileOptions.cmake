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
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
endfunction()
