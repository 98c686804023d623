// Internal to the .scn importer: the reader's state across files (scn_import.cpp) and the
// commands that fill it (scn_commands.cpp).
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/scene/scene.hpp"
#include "common/scn/scn_import.hpp"
#include "common/scn/scn_lexer.hpp"

namespace tessera::scn {

// The course's default material (gray), for objects outside any begin block that name none.
inline constexpr std::string_view default_material_name = "scn default";
// As parse_scene's: below this, a transform's 3x3 part flattens space.
inline constexpr double min_determinant = 1e-12;

// An open begin block, or a file's top level.
struct Group {
  Mat4 transform{1.0};   // object to world, every enclosing block's matrix applied
  std::string material;  // the JSON name of the block's material
  std::size_t line = 0;  // of its begin, for "unterminated begin"
};

// One file being read. Material indices count from 0 in each file, as in the course's
// reader, which started an empty list for every file it read, included ones too.
struct FileState {
  std::filesystem::path path;          // as opened: the directory of its includes and meshes
  std::string name;                    // for messages
  std::vector<std::string> materials;  // index -> the JSON name
  std::vector<Group> groups;           // groups[0] is the top level
};

// A command: its keyword and the words that follow it, up to the next keyword.
struct Command {
  Token keyword;
  std::vector<Token> words;  // at most one more than the command takes
  std::size_t count = 0;     // how many there were
};

std::string format_number(double value);

// Typed access to a command's words, each error naming the file and the word's line.
class Args {
 public:
  Args(const FileState& file, const Command& command) : file_(file), command_(command) {}

  [[noreturn]] void fail(std::size_t line, const std::string& detail) const;
  [[noreturn]] void fail_at(std::size_t word, const std::string& detail) const {
    fail(command_.words[word].line, detail);
  }
  [[noreturn]] void fail_command(const std::string& detail) const {
    fail(command_.keyword.line, detail);
  }

  std::string_view keyword() const { return command_.keyword.text; }
  std::size_t line() const { return command_.keyword.line; }
  std::size_t count() const { return command_.words.size(); }
  std::string_view word(std::size_t i) const { return command_.words[i].text; }
  double number(std::size_t i, std::string_view what) const;
  double positive(std::size_t i, std::string_view what) const;  // > 0
  double at_least_zero(std::size_t i, std::string_view what) const;
  Vec3 vec3(std::size_t i, std::string_view what) const;       // words i, i+1, i+2
  Vec3 direction(std::size_t i, std::string_view what) const;  // non-zero, as written
  Color color(std::size_t i, std::string_view what) const;     // each component >= 0
  // A material index: -1 or a whole number >= 0 (checked against the file's list later).
  long material_index(std::size_t i) const;

 private:
  const FileState& file_;
  const Command& command_;
};

class Importer {
 public:
  Importer(const ScnImportOptions& options, std::filesystem::path mesh_base)
      : options_(options), mesh_base_(std::move(mesh_base)) {}

  // Reads `file` (`name` in messages) into the scene, its objects placed by `transform`;
  // `from` is the including file and line, absent for the first file.
  void read(const std::filesystem::path& file, std::string name, const Mat4& transform,
            const Args* from);
  nlohmann::json result(const std::string& first_file);

  // The commands (scn_commands.cpp), each given its words.
  void shape(FileState& file, const Args& args);
  void mesh(FileState& file, const Args& args);
  void material(FileState& file, const Args& args);
  void light(FileState& file, const Args& args);
  void camera(FileState& file, const Args& args);
  void color_setting(FileState& file, const Args& args);
  void begin(FileState& file, const Args& args);
  void end(FileState& file, const Args& args);
  void include(FileState& file, const Args& args);

 private:
  void run_file(FileState& file, std::string_view text);
  // The JSON name of material `index` (a material_index()), or the block's for -1.
  std::string resolve_material(FileState& file, const Args& args, std::size_t word);
  void add_object(FileState& file, const Args& args, nlohmann::json object);
  std::string add_material(const Args& args, nlohmann::json material);
  void add_light(const Args& args, nlohmann::json light);
  void add_triangles(const Args& args, std::size_t count);

  const ScnImportOptions& options_;
  std::filesystem::path mesh_base_;  // absolute: mesh files are named relative to it
  nlohmann::json materials_ = nlohmann::json::object();
  nlohmann::json lights_ = nlohmann::json::array();
  nlohmann::json objects_ = nlohmann::json::array();
  std::optional<nlohmann::json> camera_;
  nlohmann::json background_ = {0.0, 0.0, 0.0};    // the course's defaults: black, and no
  nlohmann::json ambient_ = {0.0, 0.0, 0.0};       // ambient light
  std::vector<std::filesystem::path> open_files_;  // canonical, for include cycles
  std::vector<std::string> open_names_;
  std::size_t files_read_ = 0;
  std::uintmax_t bytes_read_ = 0;
  std::size_t triangles_ = 0;
  std::size_t named_materials_ = 0;
};

}  // namespace tessera::scn
