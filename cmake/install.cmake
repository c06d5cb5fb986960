# `cmake --install build --prefix P` (docs/install.md). Included at the end of
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
