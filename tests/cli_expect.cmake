# expect(<if() condition words...> MESSAGE <text>): fails the CLI test unless the condition
# holds. Included by the cli_*_test.cmake scripts.
function(expect)
  cmake_parse_arguments(PARSE_ARGV 0 arg "" "MESSAGE" "")
  if(NOT (${arg_UNPARSED_ARGUMENTS}))
    message(FATAL_ERROR "${arg_MESSAGE}")
  endif()
endfunction()
