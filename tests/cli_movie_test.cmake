# `tessera render -o movie.mp4`: an animation's frames encoded by ffmpeg. Without ffmpeg
# (MODE=missing, PATH emptied of it) the command says how to install it and renders
# nothing; with it (MODE=encode; skipped, saying so, where ffmpeg is absent) the movie
# holds every frame asked for.
# Arguments: -DTESSERA=path -DSOURCE_DIR=repo -DWORK_DIR=scratch -DMODE=missing|encode
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

include(${CMAKE_CURRENT_LIST_DIR}/cli_expect.cmake)

set(turntable "${SOURCE_DIR}/examples/animation/turntable.json")

if(MODE STREQUAL "missing")
  execute_process(
    COMMAND ${CMAKE_COMMAND} -E env PATH=${WORK_DIR}/empty
            "${TESSERA}" render "${turntable}" -o "${WORK_DIR}/turn.mp4" --width 16 --height 12
    RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  expect(code EQUAL 2 MESSAGE "a movie without ffmpeg exited ${code}: ${out} ${err}")
  string(FIND "${err}" "apt-get install ffmpeg" found)
  expect(NOT found EQUAL -1 MESSAGE "the error does not say how to install ffmpeg: ${err}")
  string(FIND "${out}" "frame 1:" found)
  expect(found EQUAL -1 MESSAGE "frames were rendered before ffmpeg was looked for: ${out}")
  expect(NOT EXISTS ${WORK_DIR}/turn.mp4 MESSAGE "a movie was written")
  return()
endif()

find_program(FFMPEG ffmpeg)
find_program(FFPROBE ffprobe)
if(NOT FFMPEG OR NOT FFPROBE)
  message("SKIPPED: ffmpeg and ffprobe are not installed (deploy/install-deps.sh installs them in a checkout)")
  return()
endif()

# Frames 1, 3, 5 and 7 at an odd size, which H.264 in 4:2:0 cannot hold: padded by one.
# The name looks like one of ffmpeg's protocols, and is a file all the same.
set(movie "${WORK_DIR}/pipe:1.mp4")
execute_process(
  COMMAND "${TESSERA}" render "${turntable}" --frames 1-7x2 -o "${movie}" --width 33
          --height 25 --spp 1
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "render -o movie failed (${code}): ${out} ${err}")
expect(EXISTS "${movie}" MESSAGE "no movie at ${movie}: ${out}")
string(FIND "${out}" "4 frames at 24 fps" found)
expect(NOT found EQUAL -1 MESSAGE "no summary line: ${out}")
execute_process(
  COMMAND "${FFPROBE}" -v error -count_frames -select_streams v:0
          -show_entries stream=codec_name,width,height,nb_read_frames -of csv=p=0 "file:${movie}"
  RESULT_VARIABLE code OUTPUT_VARIABLE probe ERROR_VARIABLE err)
string(STRIP "${probe}" probe)
expect(code EQUAL 0 MESSAGE "ffprobe failed: ${err}")
expect(probe STREQUAL "h264,34,26,4" MESSAGE "the movie is not 4 frames of H.264 at 34x26: ${probe}")
file(GLOB leftovers "${WORK_DIR}/.tessera-partial-*")
expect(NOT leftovers MESSAGE "a partial file was left behind: ${leftovers}")

# A still scene has no frames to make a movie of.
execute_process(
  COMMAND "${TESSERA}" render "${SOURCE_DIR}/examples/showcase.json" -o "${WORK_DIR}/still.mp4"
  RESULT_VARIABLE code OUTPUT_QUIET ERROR_VARIABLE err)
expect(code EQUAL 2 MESSAGE "a movie of a still scene exited ${code}: ${err}")
string(FIND "${err}" "a movie needs an animated scene" found)
expect(NOT found EQUAL -1 MESSAGE "unclear error for a still scene: ${err}")
