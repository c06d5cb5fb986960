# `cpack -G DEB` of the build, then the package's contents (the command, headers, libraries, CMake
# package, Python module) and its Depends (the Debian runtime packages plydem links against).
#   cmake -DCPACK=cpack -DBUILD=<plydem build> -DWORK=<scratch folder> [-DPETSC=ON] [-DPYTHON=ON]
#         -P check_deb.cmake
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
execute_process(COMMAND "${CPACK}" -G DEB --config "${BUILD}/CPackConfig.cmake" -B "${WORK}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
file(GLOB deb "${WORK}/*.deb")
if(NOT rc EQUAL 0 OR NOT deb)
  message(FATAL_ERROR "cpack -G DEB: exit ${rc}, no .deb:\n${out}${err}")
endif()
message(STATUS "${deb}")

execute_process(COMMAND dpkg-deb -c "${deb}" RESULT_VARIABLE rc OUTPUT_VARIABLE contents)
set(expected "./usr/bin/plydem" "./usr/include/plydem/core/model.hpp"
             "./usr/include/plydem/experiments/runner/plugin.hpp"
             "/cmake/plydem/plydemConfig.cmake" "/cmake/plydem/plydemTargets.cmake"
             "./usr/share/plydem/examples/custom_strategy/CMakeLists.txt" "/libplydem_core.a")
if(PYTHON)
  list(APPEND expected "./usr/lib/python3/dist-packages/plydem")
endif()
foreach(path IN LISTS expected)
  string(FIND "${contents}" "${path}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the package has no ${path}:\n${contents}")
  endif()
endforeach()

execute_process(COMMAND dpkg-deb -f "${deb}" Depends RESULT_VARIABLE rc OUTPUT_VARIABLE depends)
string(STRIP "${depends}" depends)
set(expected libc6 libstdc\\+\\+6 libgomp1 libfmt[0-9] libspdlog[0-9] libtomlplusplus[0-9]
             libcholmod[0-9])
if(PETSC)
  list(APPEND expected libpetsc)
endif()
if(PYTHON)
  list(APPEND expected libpython3)
endif()
foreach(package IN LISTS expected)
  if(NOT depends MATCHES "(^|, )${package}")
    message(FATAL_ERROR "Depends lacks ${package}: ${depends}")
  endif()
endforeach()
message(STATUS "Depends: ${depends}")
