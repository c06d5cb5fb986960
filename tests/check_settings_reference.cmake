# Fails when the committed reference page (PAGE, docs/settings.md) differs from what the build
# generates (COMMAND: `plydem settings`): a setting added to or changed in the settings
# descriptions needs `build/plydem settings > docs/settings.md`.
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE generated ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "`plydem settings` failed (${rc}):\n${err}")
endif()
file(READ "${PAGE}" committed)
if(NOT committed STREQUAL generated)
  file(WRITE "${OUT}" "${generated}")
  execute_process(COMMAND diff -u "${PAGE}" "${OUT}" OUTPUT_VARIABLE difference)
  message(FATAL_ERROR "${PAGE} is out of date: run `build/plydem settings > docs/settings.md`.\n"
                      "${difference}")
endif()
message(STATUS "${PAGE} is the generated reference")
