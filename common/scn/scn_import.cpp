#include "common/scn/scn_import.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <utility>

#include "common/scene/transform.hpp"
#include "common/scn/scn_importer.hpp"
#include "common/text/suggest.hpp"

namespace tessera {
namespace scn {
namespace {

using nlohmann::json;

constexpr std::size_t no_word = static_cast<std::size_t>(-1);

struct Spec {
  std::string_view keyword;
  std::size_t words;         // how many words follow the keyword
  bool last_optional;        // material's texture name may be left out
  std::size_t name_word;     // the word that is a file name rather than a number, if any
  std::string_view summary;  // what `words` are, for "sphere needs 5 numbers (...)"
  void (Importer::*run)(FileState&, const Args&);
};

// The words each command takes are those of the course's reader (R3Scene::Read), which
// read them with fscanf and so across lines.
constexpr std::array<Spec, 17> specs = {{
    {"sphere", 5, false, no_word, "5 numbers (material, x, y, z, radius)", &Importer::shape},
    {"box", 7, false, no_word, "7 numbers (material, low x, y, z, high x, y, z)", &Importer::shape},
    {"cylinder", 6, false, no_word, "6 numbers (material, x, y, z, radius, height)",
     &Importer::shape},
    {"cone", 6, false, no_word, "6 numbers (material, x, y, z, radius, height)", &Importer::shape},
    {"tri", 10, false, no_word, "10 numbers (material, x1, y1, z1, x2, y2, z2, x3, y3, z3)",
     &Importer::shape},
    {"mesh", 2, false, 1, "2 values (material, file name)", &Importer::mesh},
    {"begin", 17, false, no_word, "17 numbers (material, then a 4x4 matrix row by row)",
     &Importer::begin},
    {"end", 0, false, no_word, "no values", &Importer::end},
    {"material", 18, true, 17,
     "17 numbers and a texture name (ka r g b, kd r g b, ks r g b, kt r g b, e r g b, n, ir, "
     "texture)",
     &Importer::material},
    {"dir_light", 6, false, no_word, "6 numbers (r, g, b, dx, dy, dz)", &Importer::light},
    {"point_light", 9, false, no_word, "9 numbers (r, g, b, px, py, pz, ca, la, qa)",
     &Importer::light},
    {"spot_light", 14, false, no_word,
     "14 numbers (r, g, b, px, py, pz, dx, dy, dz, ca, la, qa, sc, sd)", &Importer::light},
    {"camera", 12, false, no_word,
     "12 numbers (eye x, y, z, towards x, y, z, up x, y, z, xfov, neardist, fardist)",
     &Importer::camera},
    {"ambient", 3, false, no_word, "3 numbers (r, g, b)", &Importer::color_setting},
    {"background", 3, false, no_word, "3 numbers (r, g, b)", &Importer::color_setting},
    {"include", 1, false, 0, "1 value (file name)", &Importer::include},
}};

// Commands of the course's reader that have no counterpart here: they are refused by name
// rather than as unknown, and end the words of the command before them.
constexpr std::array<std::string_view, 2> unsupported = {"area_light", "line"};

const Spec* find_spec(std::string_view word) {
  for (const Spec& spec : specs)
    if (spec.keyword == word) return &spec;
  return nullptr;
}

bool is_keyword(std::string_view word) {
  return find_spec(word) ||
         std::find(unsupported.begin(), unsupported.end(), word) != unsupported.end();
}

[[noreturn]] void unknown_keyword(const FileState& file, const Token& word) {
  const std::string quoted = quote_word(word.text);
  if (std::find(unsupported.begin(), unsupported.end(), word.text) != unsupported.end())
    throw ScnError(file.name, word.line, quoted + " is a COS 426 command tessera does not import");
  std::array<std::string_view, specs.size()> names;
  std::transform(specs.begin(), specs.end(), names.begin(),
                 [](const Spec& spec) { return spec.keyword; });
  std::string detail = "unknown keyword " + quoted;
  if (const auto near = closest_match(word.text, names))
    detail += "; did you mean '" + std::string(*near) + "'?";
  throw ScnError(file.name, word.line, detail);
}

void check_count(const Spec& spec, const FileState& file, const Command& command) {
  if (command.count == spec.words || (spec.last_optional && command.count + 1 == spec.words))
    return;
  // A word where a number belongs that is no number is most likely a misspelt keyword,
  // which would have ended the command before it: that is the mistake to report.
  for (std::size_t i = 0; i < command.words.size(); ++i)
    if (i != spec.name_word && !parse_number(command.words[i].text))
      unknown_keyword(file, command.words[i]);
  throw ScnError(file.name, command.keyword.line,
                 std::string(spec.keyword) + " needs " + std::string(spec.summary) + ", got " +
                     std::to_string(command.count));
}

std::string include_chain(const std::vector<std::string>& names, const std::string& next) {
  std::string chain;
  for (const std::string& name : names) chain += name + " -> ";
  return chain + next;
}

}  // namespace

void Importer::run_file(FileState& file, std::string_view text) {
  Lexer lexer(text);
  while (const auto keyword = lexer.next()) {
    const Spec* spec = find_spec(keyword->text);
    if (!spec) unknown_keyword(file, *keyword);
    Command command{*keyword, {}, 0};
    while (const auto word = lexer.peek()) {
      if (is_keyword(word->text)) break;
      lexer.next();
      // One word more than the command takes is enough to tell what went wrong.
      if (command.words.size() <= spec->words) command.words.push_back(*word);
      ++command.count;
    }
    check_count(*spec, file, command);
    (this->*spec->run)(file, Args(file, command));
  }
  if (file.groups.size() > 1) {
    throw ScnError(file.name, file.groups.back().line,
                   "begin has no matching end before the end of the file");
  }
}

void Importer::read(const std::filesystem::path& file, std::string name, const Mat4& transform,
                    const Args* from) {
  const auto fail = [&](const std::string& detail) {
    if (from) from->fail_command(detail);
    throw ScnError(name, 0, detail);
  };
  if (open_files_.size() > options_.max_include_depth) {
    fail("includes nest more than " + std::to_string(options_.max_include_depth) +
         " deep: " + include_chain(open_names_, name));
  }
  if (++files_read_ > options_.max_files) {
    fail("more than " + std::to_string(options_.max_files) +
         " files read in all (each include counts)");
  }
  std::error_code error;
  std::filesystem::path canonical = std::filesystem::weakly_canonical(file, error);
  if (error) canonical = std::filesystem::absolute(file).lexically_normal();
  if (std::find(open_files_.begin(), open_files_.end(), canonical) != open_files_.end())
    fail("include cycle: " + include_chain(open_names_, name));

  const std::uintmax_t room = options_.max_total_bytes - bytes_read_;
  const FileText text = read_bounded(file, std::min(options_.max_file_bytes, room));
  if (!text.text) {
    const std::string why = room < options_.max_file_bytes && text.error.starts_with("is larger")
                                ? "the files read so far are over " +
                                      std::to_string(options_.max_total_bytes) + " bytes in all"
                                : text.error;
    fail(from ? "cannot read included file " + name + ": " + why : "cannot read: " + why);
  }
  bytes_read_ += text.text->size();

  FileState state{
      file, std::move(name), {}, {Group{transform, std::string(default_material_name), 0}}};
  open_files_.push_back(std::move(canonical));
  open_names_.push_back(state.name);
  run_file(state, *text.text);
  open_files_.pop_back();
  open_names_.pop_back();
}

void Importer::begin(FileState& file, const Args& args) {
  if (file.groups.size() > options_.max_begin_depth) {
    args.fail_command("begin blocks nest deeper than " + std::to_string(options_.max_begin_depth));
  }
  std::array<double, 16> rows{};
  for (std::size_t i = 0; i < rows.size(); ++i)
    rows[i] = args.number(1 + i, "matrix entry " + std::to_string(i + 1));
  if (rows[12] != 0.0 || rows[13] != 0.0 || rows[14] != 0.0 || rows[15] != 1.0) {
    args.fail_at(13, "begin's matrix must be affine: its last row must be 0 0 0 1, got " +
                         format_number(rows[12]) + " " + format_number(rows[13]) + " " +
                         format_number(rows[14]) + " " + format_number(rows[15]));
  }
  const Mat4 matrix = from_row_major(rows);
  if (!(std::abs(linear_determinant(matrix)) >= min_determinant)) {
    args.fail_at(1, "begin's matrix must be invertible, but its 3x3 part has determinant " +
                        format_number(linear_determinant(matrix)));
  }
  // The course's reader kept each block's matrix relative to its parent's, so an object
  // goes through the innermost block's matrix first: outer x inner.
  Group group{file.groups.back().transform * matrix, "", args.line()};
  bool finite = true;
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 4; ++row) finite = finite && std::isfinite(group.transform[col][row]);
  if (!finite || !(std::abs(linear_determinant(group.transform)) >= min_determinant)) {
    args.fail_command(
        "begin's matrix with those of the enclosing blocks flattens space or overflows "
        "(determinant of the combined 3x3 part " +
        format_number(linear_determinant(group.transform)) + ")");
  }
  group.material = resolve_material(file, args, 0);
  file.groups.push_back(std::move(group));
}

void Importer::end(FileState& file, const Args& args) {
  if (file.groups.size() == 1) args.fail_command("end without a begin");
  file.groups.pop_back();
}

void Importer::include(FileState& file, const Args& args) {
  // Relative to the including file, as in the course's reader; an absolute name stays so.
  const std::filesystem::path path =
      (file.path.parent_path() / std::filesystem::path(std::string(args.word(0))))
          .lexically_normal();
  read(path, path.string(), file.groups.back().transform, &args);
}

json Importer::result(const std::string& first_file) {
  if (!camera_) {
    throw ScnError(first_file, 0,
                   "has no camera command; tessera needs one (the course's reader made one up "
                   "from the scene's bounding box)");
  }
  if (lights_.empty()) {
    // What the course's reader did for a scene without lights.
    lights_.push_back({{"type", "directional"}, {"direction", {-3, -4, -5}}, {"intensity", 1}});
    lights_.push_back({{"type", "directional"}, {"direction", {3, 2, 3}}, {"intensity", 0.5}});
    if (options_.warn) {
      options_.warn(first_file +
                    ": no lights; added the course reader's two default directional lights");
    }
  }
  return {{"version", 1},
          {"image", {{"width", options_.width}, {"height", options_.height}}},
          {"camera", *camera_},
          {"background", background_},
          {"ambient_light", ambient_},
          {"materials", materials_},
          {"lights", lights_},
          {"objects", objects_}};
}

}  // namespace scn

nlohmann::json import_scn(const std::filesystem::path& file, const ScnImportOptions& options) {
  const Limits& limits = options.limits;
  if (options.width < 1 || options.width > limits.max_width || options.height < 1 ||
      options.height > limits.max_height ||
      static_cast<std::uint64_t>(options.width) * static_cast<std::uint64_t>(options.height) >
          limits.max_pixels) {
    throw std::invalid_argument("image size " + std::to_string(options.width) + "x" +
                                std::to_string(options.height) + " is outside the limits");
  }
  std::filesystem::path base = options.output_dir.value_or(file.parent_path());
  if (base.empty()) base = ".";
  scn::Importer importer(options, std::filesystem::absolute(base).lexically_normal());
  importer.read(file, file.string(), Mat4(1.0), nullptr);
  return importer.result(file.string());
}

}  // namespace tessera
