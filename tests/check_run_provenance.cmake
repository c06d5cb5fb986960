# Runs COMMAND (a `plydem ... run CONFIG --out OUT` ;-list, or another program that runs a config
# through the library's runner), expects exit 0 and stdout matching
# STDOUT, then that OUT records which plydem wrote it and how: provenance.json with VERSION, a
# commit and a command line matching COMMAND_LINE (a regex); report.md with the commit and the
# command line; results.csv still opening with its header (its readers expect it on line 1).
#   cmake -DCOMMAND=plydem;run;cfg.toml;--out;dir -DOUT=dir -DVERSION=0.1.0
#         -DCOMMAND_LINE=regex -DSTDOUT=regex -P check_run_provenance.cmake
file(REMOVE_RECURSE "${OUT}")
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "expected exit 0, got ${rc}. stdout:\n${out}\nstderr:\n${err}")
endif()
if(NOT out MATCHES "${STDOUT}")
  message(FATAL_ERROR "stdout does not match '${STDOUT}':\n${out}")
endif()
file(READ "${OUT}/provenance.json" provenance)
string(JSON version GET "${provenance}" version)
string(JSON commit GET "${provenance}" commit)
string(JSON command_line GET "${provenance}" command_line)
string(JSON petsc GET "${provenance}" backends petsc)
if(NOT version STREQUAL VERSION)
  message(FATAL_ERROR "provenance.json: version '${version}', expected '${VERSION}'")
endif()
string(LENGTH "${commit}" commit_length)
if(NOT commit MATCHES "^[0-9a-f]*$" OR NOT (commit_length EQUAL 40 OR commit_length EQUAL 0))
  message(FATAL_ERROR "provenance.json: commit '${commit}' is not a commit hash")
endif()
if(NOT command_line MATCHES "${COMMAND_LINE}")
  message(FATAL_ERROR "provenance.json: command_line '${command_line}' does not match "
                      "'${COMMAND_LINE}'")
endif()
file(READ "${OUT}/report.md" report)
if(NOT report MATCHES "\n- plydem: ${VERSION}[^\n]*\n- commit: [^\n]+\n- command line: `[^`]+`")
  message(FATAL_ERROR "report.md names no version, commit and command line:\n${report}")
endif()
file(STRINGS "${OUT}/results.csv" lines LIMIT_COUNT 1)
if(NOT lines STREQUAL "experiment,case,quantity,source,value,unit")
  message(FATAL_ERROR "results.csv does not open with its header: '${lines}'")
endif()
message(STATUS "provenance.json: version ${version}, commit ${commit}, petsc ${petsc}, command "
               "line: ${command_line}")
