// The scene files of Princeton's COS 426 ray-tracing assignment (".scn") → our JSON scene
// format (docs/scene-format.md, "The COS 426 .scn format", has every keyword's mapping).
// Text in, JSON out: nothing here renders, and the JSON is checked by parse_scene later
// like any other.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "common/scene/scene.hpp"

namespace tessera {

struct ScnImportOptions {
  // The .scn has no image size, and its camera's angle is horizontal, so these also decide
  // the vertical field of view (docs/scene-format.md says why 640x480).
  int width = 640;
  int height = 480;
  // Where the JSON will be written: a mesh's file is named relative to it. Unset, relative
  // to the directory of the file given to import_scn.
  std::optional<std::filesystem::path> output_dir;
  // Counts of objects, lights and materials (and the triangles of boxes and triangles) are
  // checked against these, at the line that goes over.
  Limits limits;
  std::uintmax_t max_file_bytes = 64u << 20;    // one file
  std::uintmax_t max_total_bytes = 256u << 20;  // all files, each include counted
  std::size_t max_files = 4096;                 // files read, each include counted
  std::size_t max_include_depth = 16;           // the first file's includes are 1 deep
  std::size_t max_begin_depth = 1024;           // begin blocks open at once, in one file
  // Told about what the import added or left out but that is no error; may be empty.
  std::function<void(const std::string&)> warn;
};

// A broken .scn: "scene.scn:12: sphere needs 5 numbers (...), got 4". `line` is 0 for an
// error about the file as a whole (it cannot be read).
class ScnError : public std::runtime_error {
 public:
  ScnError(std::string file, std::size_t line, std::string detail)
      : std::runtime_error(file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " +
                           detail),
        file_(std::move(file)),
        line_(line),
        detail_(std::move(detail)) {}

  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }
  const std::string& detail() const { return detail_; }

 private:
  std::string file_;
  std::size_t line_;
  std::string detail_;
};

// Throws ScnError for anything wrong in the files, and std::invalid_argument for options
// that no scene could have (a width over the limit).
nlohmann::json import_scn(const std::filesystem::path& file, const ScnImportOptions& options = {});

}  // namespace tessera
