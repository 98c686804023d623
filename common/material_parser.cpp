#include <algorithm>
#include <string_view>

#include "common/scene_parser_parts.hpp"
#include "common/suggest.hpp"

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

Material parse_material(const ValueReader& value) {
  const ObjectReader reader(value, "a material object");
  reader.allow_only({"emission", "ambient", "diffuse", "specular", "shininess", "reflection",
                     "transmission", "ior", "checker"});
  Material m;
  m.emission = reader.color_or("emission", m.emission);
  m.ambient = reader.color_or("ambient", m.ambient);
  m.diffuse = reader.color_or("diffuse", m.diffuse);
  m.specular = reader.color_or("specular", m.specular);
  m.shininess = reader.number_or("shininess", m.shininess, Range::at_least(0.0));
  m.reflection = reader.color_or("reflection", m.specular);
  m.transmission = reader.color_or("transmission", m.transmission);
  m.ior = reader.number_or("ior", m.ior, Range::above(0.0));
  if (const auto checker = reader.find("checker")) m.checker = parse_checker(*checker, m);
  return m;
}

MaterialTable::MaterialTable(const Limits& limits)
    : max_materials_(limits.max_materials), materials_(1) {}

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
    by_name_.emplace(name, add(parse_material(value), value));
  }
}

std::uint32_t MaterialTable::resolve(const ValueReader& reference) {
  if (reference.json().is_object()) return add(parse_material(reference), reference);
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
