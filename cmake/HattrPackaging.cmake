# Debian packages of hattr (docs/install.md), made by CPack from the install components:
#   hattr           runtime: the CLI, the pen emulator, the driver plugins, share/hattr (glyphs,
#                   simulation data, the open pen's firmware)
#   hattr-studio    studio: the Qt 6 desktop studio
#   python3-hattr   python: `import hattr` for Debian's python3
#   libhattr-dev    dev: headers, static libraries and the CMake package (find_package(hattr))
# Build them from the `package` preset (prefix /usr, so the plugins go to the multiarch libdir and
# the module to /usr/lib/python3/dist-packages): `make package` writes build/package/packages/.
# The shared-library dependencies are computed by dpkg-shlibdeps from the binaries themselves;
# the others are stated here.

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME hattr)
set(CPACK_PACKAGE_VENDOR "the hattr project")
set(CPACK_PACKAGE_CONTACT "hattr developers <hattr@localhost>")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_DIRECTORY ${PROJECT_BINARY_DIR}/packages)
set(CPACK_PACKAGING_INSTALL_PREFIX ${CMAKE_INSTALL_PREFIX})
set(CPACK_STRIP_FILES ON)

set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_ENABLE_COMPONENT_DEPENDS ON)
set(CPACK_DEBIAN_PACKAGE_RELEASE 1)

# The installed components: the studio and Python only when they are built.
set(CPACK_COMPONENTS_ALL runtime dev)
if(HATTR_BUILD_STUDIO)
  list(APPEND CPACK_COMPONENTS_ALL studio)
endif()
if(HATTR_BUILD_PYTHON)
  list(APPEND CPACK_COMPONENTS_ALL python)
else()
  set(HATTR_PYTHON_VERSION 3.0)
endif()

set(_hattr_same_version "hattr (= ${PROJECT_VERSION}-${CPACK_DEBIAN_PACKAGE_RELEASE})")

set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME hattr)
# `mpirun -n N hattr sim power` (docs/cluster.md) needs Open MPI's launcher; hattr runs without it.
set(CPACK_DEBIAN_RUNTIME_PACKAGE_RECOMMENDS "openmpi-bin")
set(CPACK_COMPONENT_RUNTIME_DESCRIPTION "Motor skill training with haptic attributes: the hattr command-line tool
Records an expert's haptic profile on a force-feedback pen, trains learners against it with
position or force guidance, runs and analyses training studies; the simulated pen and trainees,
the driver plugins, the open pen's emulator and firmware, and the glyph and simulation data.")

set(CPACK_DEBIAN_STUDIO_PACKAGE_NAME hattr-studio)
set(CPACK_DEBIAN_STUDIO_PACKAGE_DEPENDS "${_hattr_same_version}")
set(CPACK_COMPONENT_STUDIO_DESCRIPTION "hattr studio: record, train and review on the virtual paper (Qt 6)")

set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-hattr)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
# The extension is built for one Python minor version (its file name says which).
string(REPLACE "." ";" _hattr_py "${HATTR_PYTHON_VERSION}")
list(GET _hattr_py 0 _hattr_py_major)
list(GET _hattr_py 1 _hattr_py_minor)
math(EXPR _hattr_py_next "${_hattr_py_minor} + 1")
set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS
    "${_hattr_same_version}, python3 (>= ${HATTR_PYTHON_VERSION}), python3 (<< ${_hattr_py_major}.${_hattr_py_next}), python3-numpy")
# Its prerm removes the bytecode Python writes beside the module (cmake/debian/python3-hattr.prerm).
configure_file(${PROJECT_SOURCE_DIR}/cmake/debian/python3-hattr.prerm ${PROJECT_BINARY_DIR}/debian/python3-hattr/prerm
               COPYONLY FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
set(CPACK_DEBIAN_PYTHON_PACKAGE_CONTROL_EXTRA ${PROJECT_BINARY_DIR}/debian/python3-hattr/prerm)
set(CPACK_COMPONENT_PYTHON_DESCRIPTION "hattr for Python: profiles as NumPy arrays, the analysis, studies and trials")

set(CPACK_DEBIAN_DEV_PACKAGE_NAME libhattr-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
    "${_hattr_same_version}, libeigen3-dev (>= 3.4), libfmt-dev, nlohmann-json3-dev, libhwy-dev, libsqlite3-dev, libsodium-dev, libzstd-dev, libpq-dev")
set(CPACK_COMPONENT_DEV_DESCRIPTION "hattr for C++: headers, static libraries and find_package(hattr)")

include(CPack)
