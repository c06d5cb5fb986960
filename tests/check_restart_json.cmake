# Checkpoint and restart from the command line: runs COMMAND (a `--json` run) three times, plainly,
# with `--checkpoint-every EVERY --checkpoint FILE`, and with `--restart FILE`, and checks that the
# three JSON objects are the same but for their wall-time keys (*seconds), that the restart said
# where it continued from, and that restarting with other settings (COMMAND plus MISMATCH) is an
# error naming the setting that differs (MISMATCH_MESSAGE); with EXPECT_LOG, that the restart's log
# says it.
#   cmake -DCOMMAND=plydem;strength;... -DEVERY=N -DFILE=path -DMISMATCH=--seed;2
#         -DMISMATCH_MESSAGE=regex -P check_restart_json.cmake
function(run_json out_var)
  execute_process(COMMAND ${COMMAND} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "exit ${rc} for ${ARGN}:\n${out}${err}")
  endif()
  # Wall times differ from run to run, and the command lines (provenance) by the flags: drop them
  # (one key per line in the indented JSON).
  string(REGEX REPLACE "\"([a-z_]*seconds|command_line)\": [^\n]*\n" "" out "${out}")
  set(${out_var} "${out}" PARENT_SCOPE)
  set(${out_var}_log "${err}" PARENT_SCOPE)
endfunction()

file(REMOVE "${FILE}")
run_json(plain)
run_json(checkpointed --checkpoint-every ${EVERY} --checkpoint "${FILE}")
if(NOT EXISTS "${FILE}")
  message(FATAL_ERROR "--checkpoint-every ${EVERY} --checkpoint ${FILE} wrote no file")
endif()
if(NOT checkpointed STREQUAL plain)
  message(FATAL_ERROR "the checkpointed run differs from the plain one:\n${checkpointed}\n---\n"
                      "${plain}")
endif()
run_json(restarted --restart "${FILE}")
if(NOT restarted_log MATCHES "restarting from")
  message(FATAL_ERROR "the restart did not say where it continued from:\n${restarted_log}")
endif()
if(EXPECT_LOG AND NOT restarted_log MATCHES "${EXPECT_LOG}")
  message(FATAL_ERROR "the restart did not say '${EXPECT_LOG}':\n${restarted_log}")
endif()
if(NOT restarted STREQUAL plain)
  message(FATAL_ERROR "the restarted run differs from the plain one:\n${restarted}\n---\n"
                      "${plain}")
endif()
message(STATUS "${restarted_log}")
if(MISMATCH)
  execute_process(COMMAND ${COMMAND} ${MISMATCH} --restart "${FILE}" RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 2 OR NOT err MATCHES "${MISMATCH_MESSAGE}")
    message(FATAL_ERROR "restarting with ${MISMATCH}: exit ${rc}, expected 2 and "
                        "'${MISMATCH_MESSAGE}':\n${out}${err}")
  endif()
  message(STATUS "with ${MISMATCH}: ${err}")
endif()
file(REMOVE "${FILE}")
