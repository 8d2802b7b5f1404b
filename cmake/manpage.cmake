# Writes a manual page from a program's --help, so the page always says what
# the program does (run by the install step, cmake/packaging.cmake).
# In: MAN_PROGRAM (the built binary), MAN_NAME, MAN_SUMMARY, MAN_VERSION,
# MAN_EXTRA (more roff sections, may be empty), MAN_OUT (.../NAME.1.gz).
execute_process(COMMAND "${MAN_PROGRAM}" --help OUTPUT_VARIABLE help RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR help STREQUAL "")
  message(FATAL_ERROR "${MAN_PROGRAM} --help failed (${rc}): no manual page")
endif()
# roff: a backslash is \e, a hyphen in an option is a minus sign (\-), and a
# line must not start with a control character.
string(REPLACE "\\" "\\e" help "${help}")
string(REPLACE "-" "\\-" help "${help}")
string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" help "${help}")
string(TOUPPER "${MAN_NAME}" upper)
get_filename_component(dir "${MAN_OUT}" DIRECTORY)
string(REGEX REPLACE "\\.gz$" "" page "${MAN_OUT}")
file(WRITE "${page}" ".TH ${upper} 1 \"\" \"${MAN_NAME} ${MAN_VERSION}\" \"User Commands\"
.nh
.SH NAME
${MAN_NAME} \\- ${MAN_SUMMARY}
.SH DESCRIPTION
.nf
${help}.fi
${MAN_EXTRA}")
execute_process(COMMAND gzip -9nf "${page}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "gzip ${page} failed: ${rc}")
endif()
file(CHMOD "${MAN_OUT}" FILE_PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ)
