#include <string_view>

#include "common/scene/scene_parser_parts.hpp"

namespace tessera {
namespace {

constexpr auto read_vec3 = [](const ValueReader& v) { return v.vec3(); };
constexpr auto read_direction = [](const ValueReader& v) { return v.direction(); };

Attenuation parse_attenuation(const ObjectReader& light) {
  Attenuation attenuation;
  const auto value = light.find("attenuation");
  if (!value) return attenuation;
  value->expect_array_of(3, "an array of 3 numbers [constant, linear, quadratic]");
  const Range non_negative = Range::at_least(0.0);
  attenuation.constant = value->element(0).number(non_negative);
  attenuation.linear = value->element(1).number(non_negative);
  attenuation.quadratic = value->element(2).number(non_negative);
  if (attenuation.constant == 0.0 && attenuation.linear == 0.0 && attenuation.quadratic == 0.0)
    value->fail("must not be all zero: the light would be infinitely bright");
  return attenuation;
}

PointLight parse_point(const ObjectReader& reader) {
  reader.allow_only({"type", "position", "intensity", "attenuation"});
  PointLight light;
  light.position = reader.require("position").animated(read_vec3);
  light.intensity = reader.animated_color_or("intensity", light.intensity);
  light.attenuation = parse_attenuation(reader);
  return light;
}

DirectionalLight parse_directional(const ObjectReader& reader) {
  reader.allow_only({"type", "direction", "intensity"});
  DirectionalLight light;
  light.direction = reader.require("direction").animated(read_direction);
  light.intensity = reader.animated_color_or("intensity", light.intensity);
  return light;
}

SpotLight parse_spot(const ObjectReader& reader) {
  reader.allow_only(
      {"type", "position", "direction", "intensity", "attenuation", "cutoff", "exponent"});
  SpotLight light;
  light.position = reader.require("position").animated(read_vec3);
  light.direction = reader.require("direction").animated(read_direction);
  light.intensity = reader.animated_color_or("intensity", light.intensity);
  light.attenuation = parse_attenuation(reader);
  light.cutoff_degrees = reader.animated_number_or("cutoff", light.cutoff_degrees,
                                                   Range::between(0.0, true, 90.0, false));
  light.exponent = reader.animated_number_or("exponent", light.exponent, Range::at_least(0.0));
  return light;
}

Light parse_light(const ValueReader& value) {
  static constexpr std::string_view types[] = {"point", "directional", "spot"};
  const ObjectReader reader(value, "a light object");
  const std::string_view type = reader.require("type").choice(types);
  if (type == "point") return parse_point(reader);
  if (type == "directional") return parse_directional(reader);
  return parse_spot(reader);
}

}  // namespace

std::vector<Light> parse_lights(const ValueReader& lights, const Limits& limits) {
  const std::size_t count = lights.array_size("an array of lights");
  if (count > limits.max_lights) {
    lights.fail_limit("must have <= " + std::to_string(limits.max_lights) +
                          " elements (limit max_lights), got " + std::to_string(count),
                      "max_lights", limits.max_lights);
  }
  std::vector<Light> result;
  result.reserve(count);
  for (std::size_t i = 0; i < count; ++i)
    result.push_back(read_every_frame(lights.element(i), parse_light));
  return result;
}

}  // namespace tessera
