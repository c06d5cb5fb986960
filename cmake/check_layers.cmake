# Fails when a source file includes a header of a layer that its own layer does not sit on.
#
#   cmake -DROOT=<source tree> -DRULES="core=|contacts=core|solvers=contacts,core|..." -P check_layers.cmake
#
# Each rule names a layer's folder and the folders below it that it may include. A file belongs to
# the layer with the longest folder that contains it; an include "folder/file.hpp" belongs to the
# layer with the longest folder that is a prefix of it. Includes of files outside every layer
# (system headers, Eigen/..., fmt/...) are not checked.
cmake_minimum_required(VERSION 3.25)
if(NOT DEFINED ROOT OR NOT DEFINED RULES)
  message(FATAL_ERROR "check_layers.cmake needs -DROOT=<dir> and -DRULES=<rules>")
endif()

string(REPLACE "|" ";" rules "${RULES}")
set(layers "")
foreach(rule IN LISTS rules)
  if(rule STREQUAL "")
    continue()
  endif()
  string(FIND "${rule}" "=" eq)
  string(SUBSTRING "${rule}" 0 ${eq} folder)
  math(EXPR after "${eq} + 1")
  string(SUBSTRING "${rule}" ${after} -1 allowed)
  string(REPLACE "," ";" allowed "${allowed}")
  list(APPEND layers "${folder}")
  string(MAKE_C_IDENTIFIER "${folder}" id)
  set(allowed_${id} "${folder};${allowed}")
endforeach()

# The layer (folder) holding a path, or "" when none does: the longest matching folder wins, so
# that experiments/protocols is not mistaken for a part of experiments.
function(layer_of path out)
  set(best "")
  string(LENGTH "" best_length)
  foreach(folder IN LISTS layers)
    string(LENGTH "${folder}/" n)
    string(SUBSTRING "${path}" 0 ${n} head)
    if(head STREQUAL "${folder}/" AND n GREATER best_length)
      set(best "${folder}")
      set(best_length ${n})
    endif()
  endforeach()
  set(${out} "${best}" PARENT_SCOPE)
endfunction()

set(violations "")
foreach(folder IN LISTS layers)
  file(GLOB_RECURSE sources RELATIVE "${ROOT}" "${ROOT}/${folder}/*.hpp" "${ROOT}/${folder}/*.cpp"
       "${ROOT}/${folder}/*.cu" "${ROOT}/${folder}/*.cuh")
  foreach(source IN LISTS sources)
    layer_of("${source}" own)
    if(NOT own STREQUAL folder)
      continue()  # belongs to a deeper layer; checked there
    endif()
    string(MAKE_C_IDENTIFIER "${own}" id)
    file(STRINGS "${ROOT}/${source}" includes REGEX "^[ \t]*#[ \t]*include[ \t]*\"[^\"]+\"")
    foreach(line IN LISTS includes)
      string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*\"([^\"]+)\".*" "\\1" header "${line}")
      layer_of("${header}" target)
      if(target STREQUAL "")
        continue()
      endif()
      list(FIND allowed_${id} "${target}" found)
      if(found EQUAL -1)
        string(APPEND violations "\n  ${source} (layer ${own}) includes \"${header}\" (layer ${target})")
      endif()
    endforeach()
  endforeach()
endforeach()

if(NOT violations STREQUAL "")
  message(FATAL_ERROR "upward or sideways includes: a layer may include only itself and the layers "
                      "below it (CMakeLists.txt, plydem_layer; docs/architecture.md, "
                      "\"Architecture\"):${violations}")
endif()
