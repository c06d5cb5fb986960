# `cmake --install` into a fresh prefix, then examples/custom_strategy as its own project against it
# (find_package(plydem)), as docs/install.md does: the installed files are where they belong, the
# example's program runs the tension test with its strategy, and the installed `plydem` loads the
# example's plug-in (--plugin and PLYDEM_PLUGIN_PATH); with PYTHON, the installed module imports.
#   cmake -DBUILD=<plydem build> -DWORK=<scratch folder> -DVERSION=0.1.0 -DLIBDIR=lib
#         -DGENERATOR=Ninja -DCXX=<compiler> [-DLAUNCHER=ccache] [-DPYTHON=/usr/bin/python3]
#         -P check_install.cmake
function(run what)
  cmake_parse_arguments(ARG "" "EXPECT;OUTPUT" "COMMAND;ENV" ${ARGN})
  execute_process(COMMAND ${CMAKE_COMMAND} -E env ${ARG_ENV} ${ARG_COMMAND} RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what}: exit ${rc}\n${ARG_COMMAND}\n${out}${err}")
  endif()
  if(ARG_EXPECT AND NOT "${out}" MATCHES "${ARG_EXPECT}")
    message(FATAL_ERROR "${what}: output does not match '${ARG_EXPECT}':\n${out}${err}")
  endif()
  message(STATUS "${what}: ok")
  if(ARG_OUTPUT)
    set(${ARG_OUTPUT} "${out}" PARENT_SCOPE)
  endif()
endfunction()

set(prefix "${WORK}/prefix")
set(example "${WORK}/example")
file(REMOVE_RECURSE "${WORK}")
run("cmake --install" COMMAND ${CMAKE_COMMAND} --install "${BUILD}" --prefix "${prefix}")

foreach(file bin/plydem include/plydem/core/model.hpp include/plydem/strategies/registry.hpp
             include/plydem/experiments/runner/plugin.hpp include/plydem/plydem_version.hpp
             ${LIBDIR}/cmake/plydem/plydemConfig.cmake
             ${LIBDIR}/cmake/plydem/plydemConfigVersion.cmake
             ${LIBDIR}/cmake/plydem/plydemTargets.cmake
             share/plydem/examples/custom_strategy/CMakeLists.txt)
  if(NOT EXISTS "${prefix}/${file}")
    message(FATAL_ERROR "cmake --install put no ${file} under ${prefix}")
  endif()
endforeach()
file(GLOB layers "${prefix}/${LIBDIR}/libplydem_*.a")
list(LENGTH layers count)
if(count LESS 9)
  message(FATAL_ERROR "cmake --install put ${count} layer libraries under ${prefix}: ${layers}")
endif()
if(EXISTS "${prefix}/include/plydem/experiments/cli")
  message(FATAL_ERROR "the command line's headers are not a library's: "
                      "include/plydem/experiments/cli")
endif()

# The example as its own project: find_package(plydem) in the prefix, nothing of the build tree.
set(configure ${CMAKE_COMMAND} -S "${prefix}/share/plydem/examples/custom_strategy" -B "${example}"
              -G "${GENERATOR}" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=${prefix}"
              "-DCMAKE_CXX_COMPILER=${CXX}")
if(LAUNCHER)
  list(APPEND configure "-DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER}")
endif()
run("configure the example with find_package(plydem)" COMMAND ${configure})
file(STRINGS "${example}/CMakeCache.txt" found REGEX "^plydem_DIR:")
if(NOT found MATCHES "${prefix}/")
  message(FATAL_ERROR "the example found plydem elsewhere than in ${prefix}: ${found}")
endif()
run("build the example" COMMAND ${CMAKE_COMMAND} --build "${example}")
run("the example's program" COMMAND "${example}/custom_strategy" --angle 30 --length-mm 2
                                    --width-mm 0.6
    EXPECT "strategy hex2d-affine.*relaxed stiffness vs target: [1-9][.][0-9]+e-0[1-4] relative")

# The installed command with the example's plug-in.
set(plugin "${example}/libcustom_strategy_plugin.so")
run("plydem --plugin strategies" COMMAND "${prefix}/bin/plydem" --plugin "${plugin}" strategies
    EXPECT "hex2d-affine +hexagonal layer with the corrected eq")
run("plydem --plugin tension --json"
    COMMAND "${prefix}/bin/plydem" tension --plugin "${plugin}" --strategy hex2d-affine --angle 30
            --length-mm 2 --width-mm 0.6 --json --quiet
    OUTPUT json)
string(JSON strategy GET "${json}" strategy)
string(JSON version GET "${json}" provenance version)
if(NOT strategy STREQUAL "hex2d-affine" OR NOT version STREQUAL VERSION)
  message(FATAL_ERROR "tension with the plug-in: strategy '${strategy}', version '${version}'")
endif()
run("PLYDEM_PLUGIN_PATH" COMMAND "${prefix}/bin/plydem" strategies
    ENV "PLYDEM_PLUGIN_PATH=${example}" EXPECT "hex2d-affine")
run("plydem --version" COMMAND "${prefix}/bin/plydem" --version EXPECT "^plydem ${VERSION}")

if(PYTHON)
  file(GLOB_RECURSE module "${prefix}/lib/python3*/plydem*.so")
  if(NOT module)
    message(FATAL_ERROR "cmake --install put no Python module under ${prefix}/lib/python3*")
  endif()
  get_filename_component(site "${module}" DIRECTORY)
  # (no ';' in the program: it would split the argument list)
  run("import plydem" COMMAND "${PYTHON}" -c "import plydem as p\nprint(p.__version__, p.__file__)"
      ENV "PYTHONPATH=${site}" EXPECT "^${VERSION} ${site}/plydem")
endif()
