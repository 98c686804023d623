# `tessera render --frames`: an animation rendered frame by frame on this machine, each
# frame written as it is done to a name with the frame number where '#' stands.
# Arguments: -DTESSERA=path -DSOURCE_DIR=repo -DWORK_DIR=scratch
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

include(${CMAKE_CURRENT_LIST_DIR}/cli_expect.cmake)

set(turntable "${SOURCE_DIR}/examples/animation/turntable.json")

# Every second frame of 1 to 5: frames 1, 3 and 5, padded to the run of '#'.
execute_process(
  COMMAND "${TESSERA}" render "${turntable}" --frames 1-5x2 -o "${WORK_DIR}/turn_####.png"
          --width 32 --height 24 --spp 1 --threads 2
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "render --frames failed (${code}): ${out} ${err}")
foreach(frame 0001 0003 0005)
  expect(EXISTS ${WORK_DIR}/turn_${frame}.png MESSAGE "turn_${frame}.png missing: ${out}")
endforeach()
expect(NOT EXISTS ${WORK_DIR}/turn_0002.png MESSAGE "frame 2 was rendered though not asked for")
foreach(frame 1 3 5)
  string(FIND "${out}" "frame ${frame}: 32x24" found)
  expect(NOT found EQUAL -1 MESSAGE "no line for frame ${frame}: ${out}")
endforeach()
# The camera moves, so the frames differ.
file(SHA256 ${WORK_DIR}/turn_0001.png first)
file(SHA256 ${WORK_DIR}/turn_0003.png third)
expect(NOT first STREQUAL third MESSAGE "frames 1 and 3 are the same image")

# Without --frames, '#' in the name renders every frame; a plain name renders the first.
execute_process(
  COMMAND "${TESSERA}" render "${turntable}" -o "${WORK_DIR}/still.png" --width 16 --height 12
          --spp 1
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "render of an animation's first frame failed: ${err}")
file(SHA256 ${WORK_DIR}/still.png still)
execute_process(
  COMMAND "${TESSERA}" render "${turntable}" --frames 1 -o "${WORK_DIR}/one_#.png" --width 16
          --height 12 --spp 1
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "render --frames 1 failed: ${err}")
file(SHA256 ${WORK_DIR}/one_1.png one)
expect(still STREQUAL one MESSAGE "the first frame differs between the two ways of asking")

# Mistakes: a frame the scene lacks, a list that cannot be read, several frames for one
# file, frames of a still scene. Each exits 2 and says what and where.
execute_process(
  COMMAND "${TESSERA}" render "${turntable}" --frames 40-50 -o "${WORK_DIR}/x_##.png"
  RESULT_VARIABLE code OUTPUT_QUIET ERROR_VARIABLE err)
expect(code EQUAL 2 MESSAGE "frame 50 of 1-48 exited ${code}: ${err}")
string(FIND "${err}" "at character 4: frame 50 is not one of the scene's, 1 to 48" found)
expect(NOT found EQUAL -1 MESSAGE "unclear error for frame 50: ${err}")
execute_process(
  COMMAND "${TESSERA}" render "${turntable}" --frames 1-4y2 -o "${WORK_DIR}/x_##.png"
  RESULT_VARIABLE code OUTPUT_QUIET ERROR_VARIABLE err)
expect(code EQUAL 2 MESSAGE "a malformed list exited ${code}: ${err}")
string(FIND "${err}" "at character 4" found)
expect(NOT found EQUAL -1 MESSAGE "the error does not name the character: ${err}")
execute_process(
  COMMAND "${TESSERA}" render "${turntable}" --frames 1-3 -o "${WORK_DIR}/plain.png"
  RESULT_VARIABLE code OUTPUT_QUIET ERROR_VARIABLE err)
expect(code EQUAL 2 MESSAGE "three frames into one file exited ${code}: ${err}")
string(FIND "${err}" "need '#'" found)
expect(NOT found EQUAL -1 MESSAGE "the error does not ask for '#': ${err}")
expect(NOT EXISTS ${WORK_DIR}/plain.png MESSAGE "an image was written anyway")
execute_process(
  COMMAND "${TESSERA}" render "${SOURCE_DIR}/examples/showcase.json" --frames 2
          -o "${WORK_DIR}/s_#.png"
  RESULT_VARIABLE code OUTPUT_QUIET ERROR_VARIABLE err)
expect(code EQUAL 2 MESSAGE "frame 2 of a still scene exited ${code}: ${err}")
string(FIND "${err}" "frame 2 is not one of the scene's, 0 to 0" found)
expect(NOT found EQUAL -1 MESSAGE "unclear error for a still scene: ${err}")
