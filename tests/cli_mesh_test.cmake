# `tessera render` of scenes that name mesh files, end to end: a real process, the files on
# disk beside the scene, exit codes and messages.
# Arguments: -DTESSERA=path -DSOURCE_DIR=repo -DBINARY_DIR=build -DWORK_DIR=scratch
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/models")

include(${CMAKE_CURRENT_LIST_DIR}/cli_expect.cmake)

# The example's OBJ and MTL are found beside the scene, from any working directory.
execute_process(
  COMMAND "${TESSERA}" render "${SOURCE_DIR}/examples/still_life.json" -o "${WORK_DIR}/still.png"
          --width 48 --height 36 --spp 1 --threads 2
  WORKING_DIRECTORY "${WORK_DIR}"
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "rendering the OBJ example failed (${code}): ${out} ${err}")
expect(EXISTS ${WORK_DIR}/still.png MESSAGE "no image written for the OBJ example")

# The generated textured example: a .glb whose texture is embedded, PNG textures beside it.
execute_process(
  COMMAND "${TESSERA}" render "${BINARY_DIR}/examples/textured_globe.json" -o "${WORK_DIR}/globe.exr"
          --width 64 --height 40 --spp 1 --threads 2
  WORKING_DIRECTORY "${WORK_DIR}"
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "rendering the textured example failed (${code}): ${out} ${err}")
expect(EXISTS ${WORK_DIR}/globe.exr MESSAGE "no image written for the textured example")

# A texture that is not there: exit 2, naming where the scene names it.
file(WRITE "${WORK_DIR}/notex.json" [=[{"image": {"width": 8, "height": 8},
  "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]},
  "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1,
               "material": {"diffuse": {"texture": "textures/none.png"}}}]}]=])
execute_process(COMMAND "${TESSERA}" render "${WORK_DIR}/notex.json" -o "${WORK_DIR}/notex.png"
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 2 MESSAGE "a missing texture exited ${code}, not 2: ${err}")
expect(err MATCHES "/objects/0/material/diffuse/texture" MESSAGE "no pointer in: ${err}")
expect(err MATCHES "textures/none.png" MESSAGE "no file named in: ${err}")

# A scene whose OFF file has a bad index: exit 2, the object's pointer, the file and line.
file(WRITE "${WORK_DIR}/models/bad.off" "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n")
file(WRITE "${WORK_DIR}/bad.json" [=[{"image": {"width": 8, "height": 8},
  "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]},
  "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1},
              {"type": "mesh", "file": "models/bad.off"}]}]=])
execute_process(COMMAND "${TESSERA}" render "${WORK_DIR}/bad.json" -o "${WORK_DIR}/bad.png"
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 2 MESSAGE "a bad mesh file exited ${code}: ${err}")
string(FIND "${err}" "/objects/1/file: models/bad.off:line 6: vertex index \"5\"" found)
expect(NOT found EQUAL -1 MESSAGE "error does not name the object, file and line: ${err}")
expect(NOT EXISTS ${WORK_DIR}/bad.png MESSAGE "an image was written for a bad mesh file")

# A model whose MTL lies outside its folder is refused, not read.
file(WRITE "${WORK_DIR}/secret.mtl" "newmtl stolen\nKd 1 0 0\n")
file(WRITE "${WORK_DIR}/models/escape.obj" "mtllib ../secret.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
file(WRITE "${WORK_DIR}/escape.json" [=[{"image": {"width": 8, "height": 8},
  "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]},
  "objects": [{"type": "mesh", "file": "models/escape.obj"}]}]=])
execute_process(COMMAND "${TESSERA}" render "${WORK_DIR}/escape.json" -o "${WORK_DIR}/escape.png"
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 2 MESSAGE "an escaping MTL exited ${code}: ${err}")
string(FIND "${err}" "outside the model's own folder" found)
expect(NOT found EQUAL -1 MESSAGE "error does not say the MTL is outside: ${err}")

# A .scn renders directly, with its included file and its OFF mesh named relative to it.
file(WRITE "${WORK_DIR}/scn/tetra.off" "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
file(WRITE "${WORK_DIR}/scn/parts.scn" "material 0.1 0.1 0.1 0.6 0.3 0.2 0.3 0.3 0.3 0 0 0 0 0 0 20 1 0\nmesh 0 tetra.off\n")
file(WRITE "${WORK_DIR}/scn/scene.scn" "camera 0.3 0.4 4 0 0 -1 0 1 0 0.5 0.1 100\npoint_light 1 1 1 2 3 4 1 0 0\n"
  "begin -1 1 0 0 -0.5 0 1 0 0 0 0 1 0 0 0 0 1\ninclude parts.scn\nend\nsphere -1 1 0 0 0.4\n")
execute_process(
  COMMAND "${TESSERA}" render "${WORK_DIR}/scn/scene.scn" -o "${WORK_DIR}/scn.png"
          --width 48 --height 36 --spp 1
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 0 MESSAGE "rendering a .scn failed (${code}): ${out} ${err}")
expect(EXISTS ${WORK_DIR}/scn.png MESSAGE "no image written for the .scn")

# A broken .scn is exit 2 with its file and line.
file(WRITE "${WORK_DIR}/bad.scn" "camera 0 0 5 0 0 -1 0 1 0 0.5 0.1 10\nsphere -1 0 0 0\n")
execute_process(COMMAND "${TESSERA}" render "${WORK_DIR}/bad.scn" -o "${WORK_DIR}/badscn.png"
  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect(code EQUAL 2 MESSAGE "a broken .scn exited ${code}: ${err}")
string(FIND "${err}" "bad.scn:2: sphere needs 5 numbers" found)
expect(NOT found EQUAL -1 MESSAGE "error does not name the .scn line: ${err}")
