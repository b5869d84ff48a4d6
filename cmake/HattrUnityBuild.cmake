# Unity builds: each target's C++ files compiled a batch at a time, so the heavy headers every
# file includes (nlohmann/json, fmt, Eigen, GoogleTest: 2.8 s to parse, against about 5 s for a
# typical file) are read once a batch instead of once a file (docs/architecture.md, "Build and CI
# in proportion").
#
# CMake's own UNITY_BUILD writes each batch as #include "/absolute/path/file.cpp", so a clone in
# another folder has other batch files and misses the compiler cache (CI builds a fresh clone).
# These batches include each file by its path from the project's root instead: the same text in
# every clone, found through -I<root>, which ccache's CCACHE_BASEDIR makes relative.
#
# A file that cannot share a batch stays on its own: one with its own compile options or
# definitions (the sample codec's -ffp-contract=off, core/install_layout.cpp), one marked SKIP_UNITY_BUILD_INCLUSION
# (Highway's per-target kernels include themselves), one that several targets compile (a batch
# hides its file from every target of the folder), and every file of a target that Qt's moc
# processes. HATTR_UNITY_BUILD=OFF compiles every file alone (to check each includes what it uses).

option(HATTR_UNITY_BUILD "Compile each target's C++ files in batches (unity build)" ON)
set(HATTR_UNITY_BATCH_SIZE 8 CACHE STRING "C++ files per unity batch")

# Whether `source` of a target may share a batch (`shared`: the folder's files in several targets).
function(hattr_unity_batchable source absolute shared result)
  set(${result} FALSE PARENT_SCOPE)
  if(NOT source MATCHES "\\.cpp$" OR absolute IN_LIST shared)
    return()
  endif()
  # Any of these set (whatever its value) keeps the file alone.
  foreach(property COMPILE_OPTIONS COMPILE_DEFINITIONS COMPILE_FLAGS INCLUDE_DIRECTORIES OBJECT_DEPENDS
                   SKIP_UNITY_BUILD_INCLUSION HEADER_FILE_ONLY)
    get_source_file_property(value ${source} ${property})
    if(NOT value STREQUAL "NOTFOUND")
      return()
    endif()
  endforeach()
  # GENERATED reads 0 when not set (and LANGUAGE the language), so they are read apart.
  get_source_file_property(generated ${source} GENERATED)
  if(generated)
    return()
  endif()
  set(${result} TRUE PARENT_SCOPE)
endfunction()

# Whether a target's files may be batched at all.
function(hattr_unity_target target result)
  get_target_property(type ${target} TYPE)
  get_target_property(automoc ${target} AUTOMOC)
  if(type STREQUAL "INTERFACE_LIBRARY" OR type STREQUAL "UTILITY" OR automoc)
    set(${result} FALSE PARENT_SCOPE)
  else()
    set(${result} TRUE PARENT_SCOPE)
  endif()
endfunction()

# Replaces a target's batchable C++ files with batches of HATTR_UNITY_BATCH_SIZE.
function(hattr_unity_build target shared)
  get_target_property(sources ${target} SOURCES)
  get_target_property(source_dir ${target} SOURCE_DIR)
  set(batchable)
  foreach(source IN LISTS sources)
    cmake_path(ABSOLUTE_PATH source BASE_DIRECTORY ${source_dir} NORMALIZE OUTPUT_VARIABLE absolute)
    hattr_unity_batchable("${source}" "${absolute}" "${shared}" ok)
    if(ok)
      list(APPEND batchable ${source})
    endif()
  endforeach()
  list(LENGTH batchable count)
  if(count LESS 2)
    return()
  endif()
  set(batch 0)
  set(in_batch 0)
  set(text "")
  foreach(source IN LISTS batchable)
    cmake_path(ABSOLUTE_PATH source BASE_DIRECTORY ${source_dir} NORMALIZE OUTPUT_VARIABLE absolute)
    file(RELATIVE_PATH from_root ${PROJECT_SOURCE_DIR} ${absolute})
    string(APPEND text "#include \"${from_root}\"\n")
    set_source_files_properties(${source} PROPERTIES HEADER_FILE_ONLY ON)
    math(EXPR in_batch "${in_batch} + 1")
    if(in_batch EQUAL HATTR_UNITY_BATCH_SIZE)
      hattr_unity_write_batch(${target} ${batch} "${text}")
      math(EXPR batch "${batch} + 1")
      set(in_batch 0)
      set(text "")
    endif()
  endforeach()
  if(in_batch GREATER 0)
    hattr_unity_write_batch(${target} ${batch} "${text}")
  endif()
  target_include_directories(${target} PRIVATE ${PROJECT_SOURCE_DIR})
endfunction()

# One batch file (rewritten only when its text changes, so a reconfigure compiles nothing).
function(hattr_unity_write_batch target batch text)
  set(file ${CMAKE_CURRENT_BINARY_DIR}/unity/${target}_${batch}.cpp)
  file(CONFIGURE OUTPUT ${file} CONTENT "// Unity batch of ${target} (cmake/HattrUnityBuild.cmake).\n${text}" @ONLY)
  target_sources(${target} PRIVATE ${file})
endfunction()

# Every target the calling CMakeLists.txt made: call at its end, after its source properties.
function(hattr_unity_build_directory)
  if(NOT HATTR_UNITY_BUILD)
    return()
  endif()
  if(NOT HATTR_UNITY_BATCH_SIZE MATCHES "^[1-9][0-9]*$")
    message(FATAL_ERROR "HATTR_UNITY_BATCH_SIZE: expected a whole number of files from 1, got \"${HATTR_UNITY_BATCH_SIZE}\"")
  endif()
  get_property(all_targets DIRECTORY PROPERTY BUILDSYSTEM_TARGETS)
  set(targets)
  set(seen)
  set(shared)
  foreach(target IN LISTS all_targets)
    hattr_unity_target(${target} ok)
    if(ok)
      list(APPEND targets ${target})
    endif()
    get_target_property(sources ${target} SOURCES)
    get_target_property(source_dir ${target} SOURCE_DIR)
    if(NOT sources)
      continue()
    endif()
    # Compared as absolute paths: two targets may name one file differently.
    foreach(source IN LISTS sources)
      cmake_path(ABSOLUTE_PATH source BASE_DIRECTORY ${source_dir} NORMALIZE OUTPUT_VARIABLE absolute)
      if(absolute IN_LIST seen)
        list(APPEND shared "${absolute}")
      endif()
      list(APPEND seen "${absolute}")
    endforeach()
  endforeach()
  foreach(target IN LISTS targets)
    hattr_unity_build(${target} "${shared}")
  endforeach()
endfunction()
