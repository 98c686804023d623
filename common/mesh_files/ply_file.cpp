// PLY (Stanford's polygon format), ASCII and binary of either byte order: a header of
// elements and their properties, then the elements' values in that order. Vertices give
// x, y, z and perhaps nx, ny, nz; faces a list "vertex_indices" (or "vertex_index"); every
// other element and property is read past.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "common/mesh_files/mesh_builder.hpp"
#include "common/mesh_files/model_source.hpp"
#include "common/mesh_files/text_lines.hpp"

namespace tessera {
namespace {

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };
enum class PlyFormat { ascii, little_endian, big_endian };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::f32;
  bool list = false;
  PlyType count_type = PlyType::u8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  std::size_t line = 0;  // of its header line
};

struct PlyHeader {
  PlyFormat format = PlyFormat::ascii;
  std::vector<PlyElement> elements;
  std::size_t body = 0;       // byte offset of the first value
  std::size_t body_line = 0;  // line number of the first value (ASCII)
};

std::optional<PlyType> type_named(std::string_view name) {
  static constexpr std::pair<std::string_view, PlyType> names[] = {
      {"char", PlyType::i8},    {"int8", PlyType::i8},     {"uchar", PlyType::u8},
      {"uint8", PlyType::u8},   {"short", PlyType::i16},   {"int16", PlyType::i16},
      {"ushort", PlyType::u16}, {"uint16", PlyType::u16},  {"int", PlyType::i32},
      {"int32", PlyType::i32},  {"uint", PlyType::u32},    {"uint32", PlyType::u32},
      {"float", PlyType::f32},  {"float32", PlyType::f32}, {"double", PlyType::f64},
      {"float64", PlyType::f64}};
  for (const auto& [n, type] : names)
    if (n == name) return type;
  return std::nullopt;
}

std::size_t size_of(PlyType type) {
  static constexpr std::size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return sizes[static_cast<int>(type)];
}

PlyType read_type(const ModelSource& source, std::size_t line, std::string_view word) {
  const auto type = type_named(word);
  if (!type) source.fail(line_at(line), "unknown property type \"" + std::string(word) + "\"");
  return *type;
}

void read_property(const ModelSource& source, std::size_t line,
                   const std::vector<std::string_view>& words, PlyHeader& header) {
  if (header.elements.empty()) source.fail(line_at(line), "a property before any element");
  PlyProperty property;
  if (words.size() == 5 && words[1] == "list") {
    property.list = true;
    property.count_type = read_type(source, line, words[2]);
    property.type = read_type(source, line, words[3]);
    property.name = words[4];
  } else if (words.size() == 3) {
    property.type = read_type(source, line, words[1]);
    property.name = words[2];
  } else {
    source.fail(line_at(line),
                "a property is \"property TYPE NAME\" or \"property list TYPE TYPE NAME\"");
  }
  header.elements.back().properties.push_back(std::move(property));
}

PlyHeader read_header(const ModelSource& source, std::string_view text) {
  TextLines lines(text);
  std::string_view line;
  std::vector<std::string_view> words;
  if (!lines.next(line) || line != "ply") source.fail("line 1", "a PLY file starts with \"ply\"");
  PlyHeader header;
  bool format_seen = false;
  while (true) {
    if (!lines.next(line)) source.fail(line_at(lines.number()), "the header has no end_header");
    split_words(line, words, false);
    const std::size_t number = lines.number();
    if (words.empty() || words[0] == "comment" || words[0] == "obj_info") continue;
    if (words[0] == "end_header") break;
    if (words[0] == "format") {
      if (words.size() != 3 || words[2] != "1.0")
        source.fail(line_at(number), "the format line is \"format KIND 1.0\"");
      if (words[1] == "ascii")
        header.format = PlyFormat::ascii;
      else if (words[1] == "binary_little_endian")
        header.format = PlyFormat::little_endian;
      else if (words[1] == "binary_big_endian")
        header.format = PlyFormat::big_endian;
      else
        source.fail(line_at(number), "unknown format \"" + std::string(words[1]) + "\"");
      format_seen = true;
    } else if (words[0] == "element") {
      const auto count = words.size() == 3 ? parse_number<std::uint64_t>(words[2]) : std::nullopt;
      if (!count) source.fail(line_at(number), "an element is \"element NAME COUNT\"");
      header.elements.push_back({std::string(words[1]), *count, {}, number});
    } else if (words[0] == "property") {
      read_property(source, number, words, header);
    } else {
      source.fail(line_at(number), "unknown header line \"" + std::string(words[0]) + "\"");
    }
  }
  if (!format_seen) source.fail("", "the header has no format line");
  header.body = lines.offset();
  header.body_line = lines.number() + 1;
  return header;
}

// The values of the body, in order, from text or bytes; every read is checked.
class PlyValues {
 public:
  PlyValues(const ModelSource& source, std::string_view text, const PlyHeader& header)
      : source_(source),
        format_(header.format),
        text_(text),
        position_(header.body),
        lines_(text.substr(header.body)),
        line_offset_(header.body_line - 1) {}

  // Called at each element instance: ASCII reads its line.
  void begin_instance() {
    if (format_ != PlyFormat::ascii) return;
    std::string_view line;
    if (!lines_.next(line)) fail("ends before its last element");
    split_words(line, words_, false);
    word_ = 0;
  }
  void end_instance() {
    if (format_ == PlyFormat::ascii && word_ != words_.size())
      fail("has " + std::to_string(words_.size()) + " values where the header says " +
           std::to_string(word_));
  }

  double number(PlyType type) {
    if (format_ == PlyFormat::ascii) {
      if (word_ >= words_.size()) fail("has too few values for its element");
      const std::string_view word = words_[word_++];
      const auto value = parse_number<double>(word);
      if (!value || !std::isfinite(*value))
        fail("\"" + std::string(word) + "\" is not a finite number");
      return *value;
    }
    return binary(type);
  }

  std::string where() const {
    return format_ == PlyFormat::ascii ? line_at(line_offset_ + lines_.number())
                                       : "byte " + std::to_string(position_);
  }
  // where() of the value of `type` just read: made only for a message, never per value.
  std::string where_last(PlyType type) const {
    return format_ == PlyFormat::ascii ? where()
                                       : "byte " + std::to_string(position_ - size_of(type));
  }
  [[noreturn]] void fail(const std::string& detail) const { source_.fail(where(), detail); }
  // For the fast paths of the common binary layouts: whether the values are little-endian
  // binary, as this machine's, the bytes not read yet, and a step past those read there.
  bool native_binary() const {
    return format_ == PlyFormat::little_endian && std::endian::native == std::endian::little;
  }
  std::string_view unread() const { return text_.substr(position_); }
  void skip(std::size_t bytes) { position_ += bytes; }
  std::size_t remaining_bytes() const {
    return format_ == PlyFormat::ascii ? lines_.remaining_bytes() : text_.size() - position_;
  }

 private:
  template <typename T>
  T load() {
    std::array<unsigned char, sizeof(T)> bytes;
    std::memcpy(bytes.data(), text_.data() + position_, sizeof(T));
    if ((format_ == PlyFormat::big_endian) == (std::endian::native == std::endian::little))
      std::reverse(bytes.begin(), bytes.end());
    position_ += sizeof(T);
    return std::bit_cast<T>(bytes);
  }

  double binary(PlyType type) {
    if (text_.size() - position_ < size_of(type)) fail("ends inside a value");
    double value = 0.0;
    switch (type) {
      case PlyType::i8:
        value = load<std::int8_t>();
        break;
      case PlyType::u8:
        value = load<std::uint8_t>();
        break;
      case PlyType::i16:
        value = load<std::int16_t>();
        break;
      case PlyType::u16:
        value = load<std::uint16_t>();
        break;
      case PlyType::i32:
        value = load<std::int32_t>();
        break;
      case PlyType::u32:
        value = load<std::uint32_t>();
        break;
      case PlyType::f32:
        value = load<float>();
        break;
      case PlyType::f64:
        value = load<double>();
        break;
    }
    if (!std::isfinite(value)) {
      position_ -= size_of(type);
      fail("holds a value that is not a finite number");
    }
    return value;
  }

  const ModelSource& source_;
  PlyFormat format_;
  std::string_view text_;
  std::size_t position_;
  TextLines lines_;
  std::size_t line_offset_;
  std::vector<std::string_view> words_;
  std::size_t word_ = 0;
};

// The fewest bytes one instance of `element` can take, for refusing counts the file cannot
// hold before anything is allocated.
std::uint64_t min_bytes(const PlyElement& element, PlyFormat format) {
  std::uint64_t bytes = 0;
  for (const PlyProperty& p : element.properties)
    bytes += format == PlyFormat::ascii ? 2 : size_of(p.list ? p.count_type : p.type);
  return std::max<std::uint64_t>(bytes, 1);
}

std::string number_text(double value) {
  if (value == std::floor(value) && std::abs(value) < 1e15)
    return std::to_string(static_cast<long long>(value));
  return std::to_string(value);
}

struct ElementReader {
  const PlyElement& element;
  PlyValues& values;
  const ModelSource& source;
};

// Vertices whose properties are all floats, little-endian, as scanners and exporters write
// them: read straight from the bytes. Returns how many were read, stopping before one that
// holds a value that is not finite, which the general path then reports.
std::uint64_t read_float_vertices(const ElementReader& in, const std::array<int, 8>& slot,
                                  RawMesh& raw) {
  const std::size_t stride = in.element.properties.size() * sizeof(float);
  const std::string_view bytes = in.values.unread();
  const std::uint64_t whole = std::min<std::uint64_t>(in.element.count, bytes.size() / stride);
  std::vector<float> v(in.element.properties.size());
  std::uint64_t i = 0;
  for (; i < whole; ++i) {
    std::memcpy(v.data(), bytes.data() + i * stride, stride);
    bool finite = true;
    for (const float value : v) finite &= std::isfinite(value);
    if (!finite) break;
    raw.positions[i] = Vec3(v[slot[0]], v[slot[1]], v[slot[2]]);
    if (!raw.normals.empty()) raw.normals[i] = Vec3(v[slot[3]], v[slot[4]], v[slot[5]]);
    if (!raw.uvs.empty()) raw.uvs[i] = Uv(v[slot[6]], v[slot[7]]);
  }
  in.values.skip(i * stride);
  return i;
}

void read_vertices(const ElementReader& in, RawMesh& raw) {
  // Texture coordinates go by three pairs of names in the wild: u v, s t, texture_u
  // texture_v; the last pair found wins.
  constexpr int kSlots = 8;
  std::array<int, kSlots> slot{-1, -1, -1, -1, -1, -1, -1, -1};
  static constexpr std::string_view names[] = {"x", "y", "z", "nx", "ny",        "nz",
                                               "u", "v", "s", "t",  "texture_u", "texture_v"};
  for (std::size_t p = 0; p < in.element.properties.size(); ++p)
    for (int k = 0; k < static_cast<int>(std::size(names)); ++k)
      if (in.element.properties[p].name == names[k] && !in.element.properties[p].list)
        slot[k < kSlots ? k : 6 + (k - 6) % 2] = static_cast<int>(p);
  if (slot[0] < 0 || slot[1] < 0 || slot[2] < 0)
    in.source.fail(line_at(in.element.line), "the vertex element has no x, y and z");
  const bool normals = slot[3] >= 0 && slot[4] >= 0 && slot[5] >= 0;
  const bool uvs = slot[6] >= 0 && slot[7] >= 0;
  raw.positions.resize(in.element.count);
  if (normals) raw.normals.resize(in.element.count);
  if (uvs) raw.uvs.resize(in.element.count);
  std::array<double, kSlots> v{};
  const auto& properties = in.element.properties;
  const bool all_floats =
      std::all_of(properties.begin(), properties.end(),
                  [](const PlyProperty& p) { return !p.list && p.type == PlyType::f32; });
  const std::uint64_t fast =
      in.values.native_binary() && all_floats ? read_float_vertices(in, slot, raw) : 0;
  for (std::uint64_t i = fast; i < in.element.count; ++i) {
    in.values.begin_instance();
    for (std::size_t p = 0; p < in.element.properties.size(); ++p) {
      const PlyProperty& property = in.element.properties[p];
      double value = 0.0;
      if (property.list) {
        const double n = in.values.number(property.count_type);
        for (double k = 0; k < n; ++k) in.values.number(property.type);
      } else {
        value = in.values.number(property.type);
      }
      for (int k = 0; k < kSlots; ++k)
        if (slot[k] == static_cast<int>(p)) v[k] = value;
    }
    in.values.end_instance();
    raw.positions[i] = Vec3(v[0], v[1], v[2]);
    if (normals) raw.normals[i] = Vec3(v[3], v[4], v[5]);
    if (uvs) raw.uvs[i] = Uv(static_cast<float>(v[6]), static_cast<float>(v[7]));
  }
}

// Faces that are triangles, each a uchar count of 3 and three 32-bit indices, little-endian,
// as most binary PLY files hold them: read straight from the bytes. Returns how many were
// read, stopping before the first face that is not such a triangle, or names a vertex that
// does not exist, or is over the limit: the general path reads on from there, and reports.
std::uint64_t read_triangle_faces(const ElementReader& in, std::uint64_t vertices,
                                  std::size_t max_triangles, RawMesh& raw) {
  constexpr std::size_t kFace = 1 + 3 * sizeof(std::uint32_t);
  const std::string_view bytes = in.values.unread();
  const std::uint64_t whole =
      std::min<std::uint64_t>({in.element.count, bytes.size() / kFace,
                               max_triangles - std::min(max_triangles, raw.triangles.size())});
  std::uint64_t f = 0;
  for (; f < whole; ++f) {
    const char* face = bytes.data() + f * kFace;
    std::array<std::uint32_t, 3> corners;
    std::memcpy(corners.data(), face + 1, sizeof corners);
    // A negative int32 reads as 2^31 or more, which no index of 2^32 - 1 vertices is
    // refused by alone; the general path tells the two apart.
    if (static_cast<unsigned char>(face[0]) != 3 || corners[0] >= vertices ||
        corners[1] >= vertices || corners[2] >= vertices ||
        ((corners[0] | corners[1] | corners[2]) >> 31) != 0)
      break;
    raw.triangles.push_back(corners);
  }
  in.values.skip(f * kFace);
  return f;
}

void read_faces(const ElementReader& in, std::uint64_t vertices, RawMesh& raw) {
  const auto is_indices = [](const PlyProperty& p) {
    return p.list && (p.name == "vertex_indices" || p.name == "vertex_index");
  };
  const auto& properties = in.element.properties;
  if (std::none_of(properties.begin(), properties.end(), is_indices))
    in.source.fail(line_at(in.element.line), "the face element has no list vertex_indices");
  const std::size_t max_triangles = in.source.request->max_triangles;
  std::vector<std::uint32_t> corners;
  raw.triangles.reserve(in.element.count);
  const std::uint64_t fast =
      in.values.native_binary() && properties.size() == 1 && is_indices(properties[0]) &&
              properties[0].count_type == PlyType::u8 &&
              (properties[0].type == PlyType::u32 || properties[0].type == PlyType::i32)
          ? read_triangle_faces(in, vertices, max_triangles, raw)
          : 0;
  for (std::uint64_t f = fast; f < in.element.count; ++f) {
    in.values.begin_instance();
    for (const PlyProperty& property : properties) {
      if (!property.list) {
        in.values.number(property.type);
        continue;
      }
      const double n = in.values.number(property.count_type);
      if (n < 0 || n != std::floor(n) || n > in.values.remaining_bytes())
        in.values.fail("a list of " + number_text(n) + " values does not fit the file");
      if (!is_indices(property)) {
        for (double k = 0; k < n; ++k) in.values.number(property.type);
        continue;
      }
      if (n < 3) in.values.fail("a face has " + std::to_string(static_cast<int>(n)) + " corners");
      corners.clear();
      for (double k = 0; k < n; ++k) {
        const double index = in.values.number(property.type);
        if (index < 0 || index != std::floor(index) || index >= static_cast<double>(vertices))
          in.source.fail(in.values.where_last(property.type),
                         "vertex index " + number_text(index) + " must be below the " +
                             std::to_string(vertices) + " vertices");
        corners.push_back(static_cast<std::uint32_t>(index));
      }
      if (raw.triangles.size() + corners.size() - 2 > max_triangles)
        in.source.fail_triangles(in.values.where(), raw.triangles.size() + corners.size() - 2);
      add_polygon(corners, raw.triangles);
    }
    in.values.end_instance();
  }
}

}  // namespace

Model read_ply(const ModelSource& source) {
  const std::string text = source.read();
  const PlyHeader header = read_header(source, text);
  PlyValues values(source, text, header);
  std::uint64_t vertices = 0;
  std::uint64_t bytes = 0;
  for (const PlyElement& element : header.elements) {
    if (element.name == "vertex") vertices = element.count;
    if (element.name == "face" && element.count > source.request->max_triangles)
      source.fail_triangles(line_at(element.line), element.count);
    const std::uint64_t least = min_bytes(element, header.format);
    if (element.count > (text.size() - header.body) / least ||
        (bytes += element.count * least) > text.size() - header.body)
      source.fail(line_at(element.line), "claims " + std::to_string(element.count) + " " +
                                             element.name + " elements, more than the file's " +
                                             std::to_string(text.size() - header.body) +
                                             " bytes of values can hold");
  }
  if (vertices > 0xffffffffu) source.fail("", "has more than 2^32 - 1 vertices");
  RawMesh raw;
  for (const PlyElement& element : header.elements) {
    const ElementReader in{element, values, source};
    if (element.name == "vertex") {
      read_vertices(in, raw);
    } else if (element.name == "face") {
      read_faces(in, vertices, raw);
    } else {
      for (std::uint64_t i = 0; i < element.count; ++i) {
        values.begin_instance();
        for (const PlyProperty& p : element.properties) {
          const double n = p.list ? values.number(p.count_type) : 1.0;
          for (double k = 0; k < n; ++k) values.number(p.type);
        }
        values.end_instance();
      }
    }
  }
  Model model;
  if (auto mesh = finish_mesh(std::move(raw), source.request->normals))
    model.parts.push_back({std::move(*mesh), std::nullopt, "PLY"});
  return model;
}

}  // namespace tessera
