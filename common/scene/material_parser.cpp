#include <algorithm>
#include <string_view>

#include "common/protocol/asset_digest.hpp"
#include "common/scene/scene_parser_parts.hpp"
#include "common/text/suggest.hpp"

namespace tessera {
namespace {

Checker parse_checker(const ValueReader& value, const Material& material) {
  const ObjectReader reader(value);
  reader.allow_only({"size", "ambient", "diffuse"});
  Checker checker;
  checker.size = reader.require("size").number(Range::above(0.0));
  checker.ambient = reader.color_or("ambient", material.ambient);
  checker.diffuse = reader.color_or("diffuse", material.diffuse);
  return checker;
}

TextureWrap read_wrap(const ObjectReader& reader) {
  const auto wrap = reader.find("wrap");
  return wrap ? enum_choice<TextureWrap>(*wrap, texture_wrap_names) : TextureWrap::repeat;
}

// {"texture": FILE, "scale": colour, "wrap": ...}, or the farm's form with "asset" (and
// "name") for "texture".
TexturedColor parse_texture(const ValueReader& value, const SceneFiles* files) {
  const ObjectReader reader(value, "a colour or a texture object");
  const bool asset = reader.members().contains("asset");
  TextureRequest request;
  const ValueReader file = reader.require(asset ? "asset" : "texture");
  if (asset) {
    reader.allow_only({"asset", "name", "scale", "wrap"});
    request.asset = read_digest(file);
    const auto name = reader.find("name");
    if (name && !name->json().is_string()) name->fail_type("a file name (string)");
    request.file =
        name ? name->string() : protocol::AssetDigest::of_hex(*request.asset).short_text();
  } else {
    reader.allow_only({"texture", "scale", "wrap"});
    if (!file.json().is_string()) file.fail_type("an image file's name (string)");
    if (file.string().empty()) file.fail("must name a file, got \"\"");
    request.file = file.string();
  }
  TexturedColor textured;
  textured.scale = reader.color_or("scale", Color(1.0));
  textured.wrap = read_wrap(reader);
  if (files == nullptr) {
    file.fail(
        "names a texture, which this reader of the scene cannot open (tessera render reads "
        "files beside the scene; tessera submit uploads them as assets)");
  }
  try {
    textured.image = files->locate_texture(request);
  } catch (const AssetNotHeld& missing) {
    throw MissingAssetError(file.pointer(), missing.digest);
  } catch (const SceneFileError& error) {
    file.fail(error.what());
  }
  return textured;
}

// A term that is a colour, or a texture object.
void read_term(const ObjectReader& reader, TexturedTerm term, Color& color, Material& m,
               const SceneFiles* files) {
  const std::string_view key = textured_term_names[static_cast<std::size_t>(term)];
  const auto value = reader.find(key);
  if (!value) return;
  if (value->json().is_object() && !value->is_track())
    m.texture(term) = parse_texture(*value, files);
  else
    color = value->animated([](const ValueReader& v) { return v.color(); }, true);
}

// Lists a few names so that an unknown-name error shows what the scene does offer.
std::string describe_names(const std::vector<std::string_view>& names) {
  constexpr std::size_t shown = 8;
  if (names.empty()) return "the scene defines no named materials";
  std::span<const std::string_view> head(names.data(), std::min(names.size(), shown));
  std::string text = "defined materials: " + quoted_list(head);
  if (names.size() > shown) text += ", ... (" + std::to_string(names.size()) + " in all)";
  return text;
}

}  // namespace

Material parse_material(const ValueReader& value, const SceneFiles* files) {
  const ObjectReader reader(value, "a material object");
  reader.allow_only({"emission", "ambient", "diffuse", "specular", "shininess", "reflection",
                     "transmission", "ior", "checker"});
  Material m;
  read_term(reader, TexturedTerm::emission, m.emission, m, files);
  read_term(reader, TexturedTerm::ambient, m.ambient, m, files);
  read_term(reader, TexturedTerm::diffuse, m.diffuse, m, files);
  read_term(reader, TexturedTerm::specular, m.specular, m, files);
  m.shininess = reader.animated_number_or("shininess", m.shininess, Range::at_least(0.0));
  m.reflection = reader.animated_color_or("reflection", m.specular);
  m.transmission = reader.animated_color_or("transmission", m.transmission);
  m.ior = reader.animated_number_or("ior", m.ior, Range::above(0.0));
  if (const auto checker = reader.find("checker")) {
    if (m.texture(TexturedTerm::ambient) || m.texture(TexturedTerm::diffuse))
      checker->fail("cannot colour a material whose ambient or diffuse term is a texture");
    m.checker = parse_checker(*checker, m);
  }
  return m;
}

MaterialTable::MaterialTable(const Limits& limits, const SceneFiles* files)
    : max_materials_(limits.max_materials), files_(files), materials_(1) {}

void MaterialTable::add_named(const ValueReader& materials) {
  const ObjectReader reader(materials, "an object mapping material names to materials");
  if (reader.members().size() > max_materials_) {
    materials.fail_limit("must have <= " + std::to_string(max_materials_) +
                             " entries (limit max_materials), got " +
                             std::to_string(reader.members().size()),
                         "max_materials", max_materials_);
  }
  for (const auto& [name, unused] : reader.members()) {
    const ValueReader value = reader.value().member(name);
    by_name_.emplace(name, add(parse_material(value, files_), value));
  }
}

std::uint32_t MaterialTable::resolve(const ValueReader& reference) {
  if (reference.json().is_object()) return add(parse_material(reference, files_), reference);
  if (!reference.json().is_string())
    reference.fail_type("a material name (string) or a material object");
  const std::string& name = reference.string();
  if (const auto found = by_name_.find(name); found != by_name_.end()) return found->second;
  std::vector<std::string_view> names;
  names.reserve(by_name_.size());
  for (const auto& [known, unused] : by_name_) names.push_back(known);
  std::string detail = "unknown material " + quote(name);
  if (const auto match = closest_match(name, names))
    detail += "; did you mean " + quote(*match) + "?";
  else
    detail += "; " + describe_names(names);
  reference.fail(detail);
}

std::uint32_t MaterialTable::add(Material material, const ValueReader& where) {
  // Index 0 is the built-in default, which the limit does not count.
  if (materials_.size() - 1 >= max_materials_) {
    where.fail_limit("is one material too many: named and inline materials together must be <= " +
                         std::to_string(max_materials_) + " (limit max_materials)",
                     "max_materials", max_materials_);
  }
  materials_.push_back(std::move(material));
  return static_cast<std::uint32_t>(materials_.size() - 1);
}

}  // namespace tessera
