# The web dashboard's files (server/web/) built into tessera-server.
#
# Included from server/CMakeLists.txt, this sets TESSERA_WEB_ASSETS_SOURCE to a C++ source in
# the build tree and adds the command that writes it, which depends on every file of
# server/web/, so that editing one rebuilds the server. Run as a script (cmake -P), with
# -DWEB_DIR=... -DOUTPUT=..., it writes that source: each file's bytes, its content type and
# the path it is served at (server/api/web_assets.hpp; server/api/web_routes.cpp serves them).
#
# index.html is served at "/", every other file at "/ui/NAME". A file whose extension has no
# content type below stops the build: the server must not guess one.

if(NOT CMAKE_SCRIPT_MODE_FILE)
  # --- configure time: the rule ---
  file(GLOB tessera_web_files CONFIGURE_DEPENDS "${CMAKE_CURRENT_LIST_DIR}/../web/*")
  list(SORT tessera_web_files)
  set(TESSERA_WEB_ASSETS_SOURCE "${CMAKE_CURRENT_BINARY_DIR}/web_assets_data.cpp")
  add_custom_command(
    OUTPUT "${TESSERA_WEB_ASSETS_SOURCE}"
    COMMAND "${CMAKE_COMMAND}" "-DWEB_DIR=${CMAKE_CURRENT_LIST_DIR}/../web"
            "-DOUTPUT=${TESSERA_WEB_ASSETS_SOURCE}" -P "${CMAKE_CURRENT_LIST_FILE}"
    DEPENDS ${tessera_web_files} "${CMAKE_CURRENT_LIST_FILE}"
    COMMENT "Building the web dashboard's files into tessera-server"
    VERBATIM)
  return()
endif()

# --- build time: the source ---
if(NOT WEB_DIR OR NOT OUTPUT)
  message(FATAL_ERROR "web_assets.cmake: run with -DWEB_DIR=DIR -DOUTPUT=FILE")
endif()
file(GLOB files RELATIVE "${WEB_DIR}" "${WEB_DIR}/*")
list(SORT files)

set(arrays "")
set(entries "")
set(count 0)
foreach(name IN LISTS files)
  if(IS_DIRECTORY "${WEB_DIR}/${name}")
    message(FATAL_ERROR "web_assets.cmake: ${WEB_DIR}/${name}: folders are not served")
  endif()
  if(NOT name MATCHES "^[A-Za-z0-9._-]+$")
    message(FATAL_ERROR "web_assets.cmake: ${name}: a served file's name is letters, digits, '.', '_' and '-'")
  endif()
  string(REGEX MATCH "[^.]*$" extension "${name}")
  string(TOLOWER "${extension}" extension)
  if(extension STREQUAL "html")
    set(type "text/html; charset=utf-8")
  elseif(extension STREQUAL "js")
    set(type "application/javascript; charset=utf-8")
  elseif(extension STREQUAL "css")
    set(type "text/css; charset=utf-8")
  elseif(extension STREQUAL "png")
    set(type "image/png")
  elseif(extension STREQUAL "svg")
    set(type "image/svg+xml")
  else()
    message(FATAL_ERROR "web_assets.cmake: ${name}: no content type for .${extension}")
  endif()
  if(name STREQUAL "index.html")
    set(path "/")
  else()
    set(path "/ui/${name}")
  endif()

  file(READ "${WEB_DIR}/${name}" hex HEX)
  string(LENGTH "${hex}" hex_length)
  math(EXPR size "${hex_length} / 2")
  # Sixteen bytes a line: "0x3c, 0x21, ..." (CMake's regular expressions count no repeats).
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1, " bytes "${hex}")
  string(REPEAT "0x[0-9a-f][0-9a-f], " 16 line_of_bytes)
  string(REGEX REPLACE "(${line_of_bytes})" "\\1\n    " bytes "${bytes}")
  string(REPLACE " \n" "\n" bytes "${bytes}")
  string(REGEX REPLACE "[ \n]+$" "" bytes "${bytes}")
  if(size EQUAL 0)
    set(bytes "0")  # an array may not be empty; the size below says 0
  endif()
  string(APPEND arrays "// ${name}, ${size} bytes.\nconst unsigned char file_${count}[] = {\n    ${bytes}};\n\n")
  string(APPEND entries "      {\"${name}\", \"${path}\", \"${type}\",\n"
                        "       std::string_view(reinterpret_cast<const char*>(file_${count}), ${size})},\n")
  math(EXPR count "${count} + 1")
endforeach()

if(count EQUAL 0)
  message(FATAL_ERROR "web_assets.cmake: ${WEB_DIR} has no files")
endif()

set(text "// Written by server/api/web_assets.cmake from server/web/ at build time: do not edit.\n")
string(APPEND text "#include \"server/api/web_assets.hpp\"\n\nnamespace tessera {\nnamespace {\n\n")
string(APPEND text "${arrays}")
string(APPEND text "}  // namespace\n\nstd::span<const WebAsset> web_assets() {\n")
string(APPEND text "  static const WebAsset assets[] = {\n${entries}  };\n  return assets;\n}\n\n")
string(APPEND text "}  // namespace tessera\n")

# Only a changed source is written, so that an unchanged one compiles no more.
set(old "")
if(EXISTS "${OUTPUT}")
  file(READ "${OUTPUT}" old)
endif()
if(NOT old STREQUAL text)
  file(WRITE "${OUTPUT}" "${text}")
endif()
