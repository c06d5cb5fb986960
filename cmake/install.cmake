# `cmake --install build --prefix P` and `cpack -G DEB` (docs/install.md). Included at the end of
# CMakeLists.txt, when every target exists.
#   P/bin/plydem                          the command (its plydem symbols exported for plug-ins)
#   P/lib/libplydem_<layer>.a             one static library per layer
#   P/include/plydem/<layer>/*.hpp        the layers' public headers, plydem_version.hpp
#   P/lib/cmake/plydem/                   plydemConfig.cmake, its version file and the targets:
#                                         plydem::plydem (everything), plydem::<layer>
#                                         (plydem::core, ...), plydem::plugin (a plug-in's headers)
#   P/share/plydem/examples/custom_strategy   a project that builds against it (find_package)
#   Python's module, `import plydem`      where Debian's python3 finds it (python/CMakeLists.txt)
include(CMakePackageConfigHelpers)

install(TARGETS plydem_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

set(PLYDEM_EXPORTED_TARGETS ${PLYDEM_LAYERS} plydem plydem_plugin)
if(PLYDEM_CUDA)
  set_target_properties(plydem_cuda PROPERTIES EXPORT_NAME cuda)
  list(APPEND PLYDEM_EXPORTED_TARGETS plydem_cuda)
endif()
install(TARGETS ${PLYDEM_EXPORTED_TARGETS} EXPORT plydemTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(EXPORT plydemTargets NAMESPACE plydem:: DESTINATION ${PLYDEM_INSTALL_CMAKEDIR})

# The public headers: every layer's, as the sources include them ("core/model.hpp"). The command
# line's (experiments/cli) and the Python module's are not a library's.
foreach(folder IN ITEMS core contacts solvers packings strategies experiments/protocols
                        experiments/output experiments/fem experiments/runner)
  install(DIRECTORY ${folder}/ DESTINATION ${PLYDEM_INSTALL_INCLUDEDIR}/${folder}
          FILES_MATCHING PATTERN "*.hpp")
endforeach()
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/generated/include/plydem_version.hpp
        DESTINATION ${PLYDEM_INSTALL_INCLUDEDIR})

# The package: find_package(plydem) finds the Debian packages the libraries link through
# find_dependency (cmake/plydemConfig.cmake.in), then the targets.
configure_package_config_file(cmake/plydemConfig.cmake.in
                              ${CMAKE_CURRENT_BINARY_DIR}/generated/plydemConfig.cmake
                              INSTALL_DESTINATION ${PLYDEM_INSTALL_CMAKEDIR})
# A 0.x version promises nothing across minor versions; a plug-in must match exactly anyway
# (experiments/runner/plugin.hpp).
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/generated/plydemConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/generated/plydemConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/generated/plydemConfigVersion.cmake
        DESTINATION ${PLYDEM_INSTALL_CMAKEDIR})

# The example built against the installed package (tests: install_find_package).
install(DIRECTORY examples/custom_strategy/
        DESTINATION ${CMAKE_INSTALL_DATADIR}/plydem/examples/custom_strategy)

# --- Debian package: `cpack -G DEB` in the build folder ------------------------------------------
# Depends: the runtime packages of the shared libraries bin/plydem and the Python module link
# (dpkg-shlibdeps); Recommends: the -dev packages that find_package(plydem) needs to build against
# the headers and static libraries. Installed under /usr with DESTDIR, so that the Python module's
# install (python/CMakeLists.txt) sees the prefix /usr and goes where Debian's python3 looks.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME plydem)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "plydem maintainers")
string(CONCAT CPACK_PACKAGE_DESCRIPTION_SUMMARY
       "particle (DEM) models of fibre-reinforced composite laminae: the plydem command, C++ "
       "libraries, headers, CMake package and Python module")
set(CPACK_SET_DESTDIR ON)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_INSTALL_PREFIX /usr)  # the prefix the install sees under CPACK_SET_DESTDIR
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
string(CONCAT CPACK_DEBIAN_PACKAGE_RECOMMENDS
       "cmake, g++, libeigen3-dev, libboost-dev, libfmt-dev, libspdlog-dev, libtomlplusplus-dev, "
       "nlohmann-json3-dev, libsuitesparse-dev, libcli11-dev")
if(PLYDEM_PETSC)
  string(APPEND CPACK_DEBIAN_PACKAGE_RECOMMENDS ", petsc-dev, pkg-config")
endif()
include(CPack)
