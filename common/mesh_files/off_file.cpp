// OFF, the mesh format of the COS 426 course (and Geomview's): an optional "OFF" header,
// the counts "vertices faces edges", one vertex per line, then one polygon per line as
// "n i1 ... in" with optional colours after; '#' starts a comment.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "common/mesh_files/mesh_builder.hpp"
#include "common/mesh_files/model_source.hpp"
#include "common/mesh_files/text_lines.hpp"

namespace tessera {
namespace {

struct OffHeader {
  bool normals = false;  // "NOFF": each vertex line has its normal after the point
  std::uint64_t vertices = 0;
  std::uint64_t faces = 0;
};

// The next line with words on it; false at the end of the file.
bool next_words(TextLines& lines, std::vector<std::string_view>& words) {
  std::string_view line;
  while (lines.next(line)) {
    split_words(line, words);
    if (!words.empty()) return true;
  }
  return false;
}

std::uint64_t count(const ModelSource& source, const TextLines& lines, std::string_view word,
                    const char* what) {
  const auto value = parse_number<std::uint64_t>(word);
  if (!value) {
    source.fail(line_at(lines.number()), std::string("the ") + what +
                                             " count must be a non-negative integer, got \"" +
                                             std::string(word) + "\"");
  }
  return *value;
}

OffHeader read_header(const ModelSource& source, TextLines& lines,
                      std::vector<std::string_view>& words) {
  OffHeader header;
  if (!next_words(lines, words)) source.fail("", "is empty: an OFF file starts with its counts");
  std::size_t first = 0;
  const std::string_view keyword = words[0];
  if (keyword.size() >= 3 && keyword.substr(keyword.size() - 3) == "OFF") {
    const std::string_view prefix = keyword.substr(0, keyword.size() - 3);
    for (const char c : prefix) {
      if (c == 'N') {
        header.normals = true;
      } else if (c != 'C' && c != 'S' && c != 'T') {  // colours, texture coordinates: ignored
        source.fail(line_at(lines.number()), "\"" + std::string(keyword) +
                                                 "\" is not an OFF header this reader knows "
                                                 "(OFF, COFF, NOFF, STOFF and their mixes)");
      }
    }
    first = 1;
    if (words.size() == 1) {  // the counts on a line of their own
      if (!next_words(lines, words))
        source.fail(line_at(lines.number()), "ends before the counts line");
      first = 0;
    }
  }
  if (words.size() < first + 2) {
    source.fail(line_at(lines.number()),
                "the counts line must be \"vertices faces [edges]\", got " +
                    std::to_string(words.size() - first) + " numbers");
  }
  header.vertices = count(source, lines, words[first], "vertex");
  header.faces = count(source, lines, words[first + 1], "face");
  // Before anything is allocated: each vertex and each face takes at least five bytes
  // ("0 0 0", "3 0 1 2" is seven), and each face is at least one triangle.
  const std::string where = line_at(lines.number());
  if (header.faces > source.request->max_triangles) source.fail_triangles(where, header.faces);
  if (header.vertices > 0xffffffffu || header.faces > lines.remaining_bytes() ||
      (header.vertices + header.faces) * 5 > lines.remaining_bytes())
    source.fail(where, "claims " + std::to_string(header.vertices) + " vertices and " +
                           std::to_string(header.faces) + " faces, more than its " +
                           std::to_string(lines.remaining_bytes()) + " remaining bytes can hold");
  return header;
}

Vec3 read_vec3(const ModelSource& source, const TextLines& lines,
               const std::vector<std::string_view>& words, std::size_t first) {
  Vec3 v;
  for (int k = 0; k < 3; ++k) {
    const auto value = parse_number<double>(words[first + k]);
    if (!value || !std::isfinite(*value)) {
      source.fail(line_at(lines.number()), "coordinate " + std::to_string(first + k + 1) +
                                               " must be a finite number, got \"" +
                                               std::string(words[first + k]) + "\"");
    }
    v[k] = *value;
  }
  return v;
}

}  // namespace

Model read_off(const ModelSource& source) {
  const std::string text = source.read();
  TextLines lines(text);
  std::vector<std::string_view> words;
  const OffHeader header = read_header(source, lines, words);
  RawMesh raw;
  raw.positions.reserve(header.vertices);
  if (header.normals) raw.normals.reserve(header.vertices);
  const std::size_t needed = header.normals ? 6 : 3;
  for (std::uint64_t i = 0; i < header.vertices; ++i) {
    if (!next_words(lines, words))
      source.fail(line_at(lines.number()), "ends after " + std::to_string(i) + " of " +
                                               std::to_string(header.vertices) + " vertices");
    if (words.size() < needed) {
      source.fail(line_at(lines.number()), "a vertex needs " + std::to_string(needed) +
                                               " numbers, got " + std::to_string(words.size()));
    }
    raw.positions.push_back(read_vec3(source, lines, words, 0));
    if (header.normals) raw.normals.push_back(read_vec3(source, lines, words, 3));
  }
  std::vector<std::uint32_t> corners;
  for (std::uint64_t f = 0; f < header.faces; ++f) {
    if (!next_words(lines, words))
      source.fail(line_at(lines.number()), "ends after " + std::to_string(f) + " of " +
                                               std::to_string(header.faces) + " faces");
    const auto n = parse_number<std::uint64_t>(words[0]);
    if (!n || *n < 3 || *n > words.size() - 1) {
      source.fail(line_at(lines.number()),
                  "a face is \"n i1 ... in\" with n >= 3 and n indices, got \"" +
                      std::string(words[0]) + "\" then " + std::to_string(words.size() - 1) +
                      " numbers");
    }
    corners.clear();
    for (std::uint64_t k = 1; k <= *n; ++k) {
      const auto index = parse_number<std::uint64_t>(words[k]);
      if (!index || *index >= header.vertices) {
        source.fail(line_at(lines.number()), "vertex index \"" + std::string(words[k]) +
                                                 "\" must be below the " +
                                                 std::to_string(header.vertices) + " vertices");
      }
      corners.push_back(static_cast<std::uint32_t>(*index));
    }
    if (raw.triangles.size() + corners.size() - 2 > source.request->max_triangles)
      source.fail_triangles(line_at(lines.number()), raw.triangles.size() + corners.size() - 2);
    add_polygon(corners, raw.triangles);
  }
  Model model;
  if (auto mesh = finish_mesh(std::move(raw), source.request->normals))
    model.parts.push_back({std::move(*mesh), std::nullopt, "OFF"});
  return model;
}

}  // namespace tessera
