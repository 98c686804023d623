# `tessera render` end to end as a user runs it: a real process, real files, exit codes.
# Arguments: -DTESSERA=path -DSOURCE_DIR=repo -DWORK_DIR=scratch
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

include(${CMAKE_CURRENT_LIST_DIR}/cli_expect.cmake)

# A good scene renders, reports its rays and writes the image.
execute_process(
  COMMAND "${TESSERA}" render "${SOURCE_DIR}/examples/showcase.json" -o "${WORK_DIR}/out.png"
          --width 64 --height 48 --spp 1 --threads 2
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "render failed (${code}): ${out} ${err}")
expect(EXISTS ${WORK_DIR}/out.png MESSAGE "no image written")
string(FIND "${out}" "Mrays/s" found)
expect(NOT found EQUAL -1 MESSAGE "no ray rate printed: ${out}")
string(FIND "${out}" "rays: " found)
expect(NOT found EQUAL -1 MESSAGE "no ray count printed: ${out}")

# EXR output by extension.
execute_process(
  COMMAND "${TESSERA}" render "${SOURCE_DIR}/examples/showcase.json" -o "${WORK_DIR}/out.exr"
          --width 32 --height 24 --spp 1
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "exr render failed (${code}): ${err}")
expect(EXISTS ${WORK_DIR}/out.exr MESSAGE "no exr written")

# A broken scene: non-zero exit, the JSON Pointer in the message, no image.
file(WRITE "${WORK_DIR}/bad.json" [=[{"image": {"width": 8, "height": 8},
  "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]},
  "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": -1}]}]=])
execute_process(
  COMMAND "${TESSERA}" render "${WORK_DIR}/bad.json" -o "${WORK_DIR}/bad.png"
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(NOT code EQUAL 0 MESSAGE "a broken scene exited 0")
string(FIND "${err}" "/objects/0/radius" found)
expect(NOT found EQUAL -1 MESSAGE "error does not name the JSON Pointer: ${err}")
expect(NOT EXISTS ${WORK_DIR}/bad.png MESSAGE "an image was written for a broken scene")

# An override that breaks a limit is reported like a value in the file.
execute_process(
  COMMAND "${TESSERA}" render "${SOURCE_DIR}/examples/showcase.json" -o "${WORK_DIR}/x.png"
          --width 20000
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(NOT code EQUAL 0 MESSAGE "an over-limit width exited 0")
string(FIND "${err}" "/image/width" found)
expect(NOT found EQUAL -1 MESSAGE "error does not name /image/width: ${err}")

# Malformed JSON names line and column; a missing file is a clear error.
file(WRITE "${WORK_DIR}/broken.json" "{\n  \"image\": {\"width\": 8,,}\n}\n")
execute_process(COMMAND "${TESSERA}" render "${WORK_DIR}/broken.json"
  RESULT_VARIABLE code ERROR_VARIABLE err OUTPUT_QUIET)
expect(NOT code EQUAL 0 MESSAGE "malformed JSON exited 0")
string(FIND "${err}" "line 2" found)
expect(NOT found EQUAL -1 MESSAGE "error does not name the line: ${err}")
execute_process(COMMAND "${TESSERA}" render "${WORK_DIR}/missing.json"
  RESULT_VARIABLE code ERROR_VARIABLE err OUTPUT_QUIET)
expect(code EQUAL 2 MESSAGE "a missing scene file exited ${code}, not 2 (usage, as for submit)")
execute_process(COMMAND "${TESSERA}" submit "${WORK_DIR}/missing.json" --server http://127.0.0.1:1
  RESULT_VARIABLE code ERROR_VARIABLE err OUTPUT_QUIET)
expect(code EQUAL 2 MESSAGE "submit of a missing scene file exited ${code}, not 2")

# --version, and the global options after the subcommand as before it.
execute_process(COMMAND "${TESSERA}" --version RESULT_VARIABLE code OUTPUT_VARIABLE out)
expect(code EQUAL 0 MESSAGE "--version exited ${code}")
string(REGEX MATCH "^tessera [0-9]+\\.[0-9]+\\.[0-9]+" version "${out}")
expect(version MESSAGE "--version printed: ${out}")
execute_process(COMMAND "${TESSERA}" list --json --server http://127.0.0.1:1
  RESULT_VARIABLE code ERROR_VARIABLE err OUTPUT_QUIET)
expect(code EQUAL 3 MESSAGE "list --json --server ... exited ${code} (not unreachable): ${err}")

# A usage error is one line, "error: ...", and exit code 2, as every other error: a missing
# argument, an unknown command, a value out of range.
foreach(args "submit" "frobnicate" "list;--limit;x")
  execute_process(COMMAND "${TESSERA}" ${args}
    RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  expect(code EQUAL 2 MESSAGE "tessera ${args}: exit ${code}, not 2")
  string(REGEX MATCHALL "\n" lines "${err}")
  list(LENGTH lines count)
  expect(count EQUAL 1 MESSAGE "tessera ${args}: not one line: ${err}")
  string(FIND "${err}" "error: " at)
  expect(at EQUAL 0 MESSAGE "tessera ${args}: not an error: line: ${err}")
endforeach()
