# `tessera import` end to end: a real process, real files, exit codes.
# Arguments: -DTESSERA=path -DWORK_DIR=scratch
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/scenes" "${WORK_DIR}/meshes" "${WORK_DIR}/out")

include(${CMAKE_CURRENT_LIST_DIR}/cli_expect.cmake)

# A .scn scene becomes a JSON scene that renders.
file(WRITE "${WORK_DIR}/scenes/room.scn" [=[
# a sphere on a floor, lit three ways
camera 0 1 6  0 -0.1 -1  0 1 0  0.4  0.01 100
material 0.1 0.1 0.1  0.8 0.2 0.2  0.4 0.4 0.4  0 0 0  0 0 0  30 1 0
dir_light 0.4 0.4 0.4  -1 -1 -1
point_light 0.6 0.6 0.6  2 4 3  1 0 0.02
spot_light 1 1 1  0 4 0  0 -1 0  1 0 0  0.5 2
box -1  -4 -1 -4  4 0 4
begin 0  1 0 0 0  0 1 0 1  0 0 1 0  0 0 0 1
  sphere -1  0 0 0  1
end
]=])
execute_process(
  COMMAND "${TESSERA}" import "${WORK_DIR}/scenes/room.scn" -o "${WORK_DIR}/out/room.json"
          --width 32 --height 24
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "import failed (${code}): ${out} ${err}")
file(READ "${WORK_DIR}/out/room.json" scene)
string(JSON width GET "${scene}" image width)
expect(width EQUAL 32 MESSAGE "image.width is ${width}, not --width 32")
string(JSON cutoff GET "${scene}" lights 2 cutoff)
expect(cutoff GREATER 28.6 AND cutoff LESS 28.7 MESSAGE "spot cutoff ${cutoff}, not 0.5 rad in degrees")
execute_process(
  COMMAND "${TESSERA}" render "${WORK_DIR}/out/room.json" -o "${WORK_DIR}/out/room.png" --threads 2
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "the imported scene did not render (${code}): ${err}")
expect(EXISTS "${WORK_DIR}/out/room.png" MESSAGE "no image rendered from the imported scene")

# A mesh's file is named from the JSON's folder, not the .scn's.
file(WRITE "${WORK_DIR}/meshes/tri.off" "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
file(WRITE "${WORK_DIR}/scenes/mesh.scn"
  "camera 0 0 5  0 0 -1  0 1 0  0.5  0.01 100\nmesh -1 ../meshes/tri.off\n")
execute_process(
  COMMAND "${TESSERA}" import "${WORK_DIR}/scenes/mesh.scn" -o "${WORK_DIR}/mesh.json"
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "mesh import failed (${code}): ${err}")
file(READ "${WORK_DIR}/mesh.json" scene)
string(JSON mesh_file GET "${scene}" objects 0 file)
expect(mesh_file STREQUAL "meshes/tri.off" MESSAGE "mesh file written as ${mesh_file}")

# A broken .scn: exit 2, the file and line in the message, no JSON written.
file(WRITE "${WORK_DIR}/scenes/bad.scn"
  "camera 0 0 5  0 0 -1  0 1 0  0.5  0.01 100\nsphere 0 1 2 3\n")
execute_process(
  COMMAND "${TESSERA}" import "${WORK_DIR}/scenes/bad.scn" -o "${WORK_DIR}/out/bad.json"
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 2 MESSAGE "a broken .scn exited ${code}, not 2: ${err}")
string(FIND "${err}" "bad.scn:2: sphere needs 5 numbers (material, x, y, z, radius), got 4" found)
expect(NOT found EQUAL -1 MESSAGE "error does not name the file and line: ${err}")
expect(NOT EXISTS "${WORK_DIR}/out/bad.json" MESSAGE "JSON written for a broken .scn")

# A missing .scn is a usage error, as a missing scene is for render.
execute_process(COMMAND "${TESSERA}" import "${WORK_DIR}/missing.scn" -o "${WORK_DIR}/m.json"
  RESULT_VARIABLE code ERROR_VARIABLE err OUTPUT_QUIET)
expect(code EQUAL 2 MESSAGE "a missing .scn exited ${code}, not 2: ${err}")
