// The .scn commands that add to the scene: shapes, materials, lights, the camera.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <string>

#include "common/scene/scene_files.hpp"
#include "common/scn/scn_importer.hpp"

namespace tessera::scn {
namespace {

using nlohmann::json;

constexpr double min_up_sine = 1e-6;  // as parse_scene's camera

json to_json(const Vec3& v) { return {v.x, v.y, v.z}; }

json row_major(const Mat4& m) {
  json rows = json::array();
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col) rows.push_back(m[col][row]);
  return rows;
}

Vec3 unit(const Vec3& v) { return v / std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)}); }

}  // namespace

std::string format_number(double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  return std::string(text, end);
}

void Args::fail(std::size_t line, const std::string& detail) const {
  throw ScnError(file_.name, line, detail);
}

double Args::number(std::size_t i, std::string_view what) const {
  const auto value = parse_number(word(i));
  if (!value) {
    fail_at(i, std::string(keyword()) + " " + std::string(what) + " must be a number, got " +
                   quote_word(word(i)));
  }
  return *value;
}

double Args::positive(std::size_t i, std::string_view what) const {
  const double value = number(i, what);
  if (!(value > 0.0))
    fail_at(i, std::string(keyword()) + " " + std::string(what) + " must be > 0, got " +
                   format_number(value));
  return value;
}

double Args::at_least_zero(std::size_t i, std::string_view what) const {
  const double value = number(i, what);
  if (!(value >= 0.0))
    fail_at(i, std::string(keyword()) + " " + std::string(what) + " must be >= 0, got " +
                   format_number(value));
  return value;
}

Vec3 Args::vec3(std::size_t i, std::string_view what) const {
  const std::string name(what);
  return {number(i, name + " x"), number(i + 1, name + " y"), number(i + 2, name + " z")};
}

Vec3 Args::direction(std::size_t i, std::string_view what) const {
  const Vec3 v = vec3(i, what);
  if (v == Vec3(0.0))
    fail_at(i, std::string(keyword()) + " " + std::string(what) + " must not be 0 0 0");
  return v;
}

Color Args::color(std::size_t i, std::string_view what) const {
  const std::string name = what.empty() ? "" : std::string(what) + " ";
  return {at_least_zero(i, name + "r"), at_least_zero(i + 1, name + "g"),
          at_least_zero(i + 2, name + "b")};
}

long Args::material_index(std::size_t i) const {
  const double value = number(i, "material");
  if (value != std::floor(value) || value < -1.0 || value > 1e9) {
    fail_at(i, std::string(keyword()) + " material must be -1 or the index of a material, got " +
                   quote_word(word(i)));
  }
  return static_cast<long>(value);
}

std::string Importer::resolve_material(FileState& file, const Args& args, std::size_t word) {
  const long index = args.material_index(word);
  if (index < 0) return file.groups.back().material;
  if (static_cast<std::size_t>(index) >= file.materials.size()) {
    const std::size_t count = file.materials.size();
    args.fail_at(
        word, "material " + std::to_string(index) + " is not defined: " +
                  (count == 0 ? std::string("this file defines none before this line")
                              : "this file defines " + std::to_string(count) +
                                    " before this line (0 to " + std::to_string(count - 1) + ")"));
  }
  return file.materials[static_cast<std::size_t>(index)];
}

std::string Importer::add_material(const Args& args, json material) {
  if (materials_.size() >= options_.limits.max_materials) {
    args.fail_command("more than " + std::to_string(options_.limits.max_materials) +
                      " materials (limit max_materials)");
  }
  std::string name = "m" + std::to_string(named_materials_++);
  materials_[name] = std::move(material);
  return name;
}

void Importer::add_object(FileState& file, const Args& args, json object) {
  if (objects_.size() >= options_.limits.max_objects) {
    args.fail_command("more than " + std::to_string(options_.limits.max_objects) +
                      " objects (limit max_objects)");
  }
  std::string material = resolve_material(file, args, 0);
  if (material == default_material_name && !materials_.contains(material)) {
    if (materials_.size() >= options_.limits.max_materials) {
      args.fail_command("more than " + std::to_string(options_.limits.max_materials) +
                        " materials (limit max_materials)");
    }
    materials_[material] = {{"ambient", 0.2},    {"diffuse", 0.5}, {"specular", 0.5},
                            {"transmission", 0}, {"emission", 0},  {"shininess", 10},
                            {"ior", 1}};
  }
  object["material"] = std::move(material);
  const Mat4& transform = file.groups.back().transform;
  if (transform != Mat4(1.0))
    object["transform"] = json::array({{{"matrix", row_major(transform)}}});
  objects_.push_back(std::move(object));
}

void Importer::add_triangles(const Args& args, std::size_t count) {
  triangles_ += count;
  if (triangles_ > options_.limits.max_triangles) {
    args.fail_command("more than " + std::to_string(options_.limits.max_triangles) +
                      " triangles in boxes and triangles (limit max_triangles)");
  }
}

void Importer::shape(FileState& file, const Args& args) {
  const std::string_view kind = args.keyword();
  json object;
  if (kind == "sphere") {
    object = {{"type", "sphere"},
              {"center", to_json(args.vec3(1, "center"))},
              {"radius", args.positive(4, "radius")}};
  } else if (kind == "box") {
    const Vec3 low = args.vec3(1, "low");
    const Vec3 high = args.vec3(4, "high");
    for (int axis = 0; axis < 3; ++axis) {
      if (!(low[axis] < high[axis])) {
        args.fail_at(4 + axis, "box high corner must be greater than the low one in x, y and z");
      }
    }
    add_triangles(args, 12);
    object = {{"type", "box"}, {"min", to_json(low)}, {"max", to_json(high)}};
  } else if (kind == "tri") {
    const Vec3 a = args.vec3(1, "corner 1");
    const Vec3 b = args.vec3(4, "corner 2");
    const Vec3 c = args.vec3(7, "corner 3");
    if (is_degenerate(a, b, c))
      args.fail_command("tri is degenerate: its corners coincide or lie on one line");
    add_triangles(args, 1);
    object = {{"type", "triangle"}, {"vertices", {to_json(a), to_json(b), to_json(c)}}};
  } else {  // cylinder and cone: about the object's y axis, centred on `center`
    object = {{"type", std::string(kind)},
              {"center", to_json(args.vec3(1, "center"))},
              {"radius", args.positive(4, "radius")},
              {"height", args.positive(5, "height")}};
  }
  add_object(file, args, std::move(object));
}

void Importer::mesh(FileState& file, const Args& args) {
  // Named relative to the .scn file, as in the course's reader; written relative to where
  // the JSON goes, so that both name the same file.
  const std::filesystem::path named(std::string(args.word(1)));
  const std::filesystem::path target =
      std::filesystem::absolute(file.path.parent_path() / named).lexically_normal();
  std::error_code error;
  if (!std::filesystem::is_regular_file(target, error)) {
    args.fail_at(1, "mesh file " + quote_word(args.word(1)) + " not found (looked for " +
                        target.string() + ")");
  }
  std::filesystem::path written = target;
  if (!named.is_absolute()) written = target.lexically_relative(mesh_base_);
  if (written.empty()) written = target;  // no relative path between them
  add_object(file, args, {{"type", "mesh"}, {"file", written.generic_string()}});
}

void Importer::material(FileState& file, const Args& args) {
  json material = {{"ambient", to_json(args.color(0, "ka"))},
                   {"diffuse", to_json(args.color(3, "kd"))},
                   {"specular", to_json(args.color(6, "ks"))},
                   {"transmission", to_json(args.color(9, "kt"))},
                   {"emission", to_json(args.color(12, "e"))},
                   {"shininess", args.at_least_zero(15, "n")},
                   {"ior", args.positive(16, "ir")}};
  if (args.count() == 18 && args.word(17) != "0") {
    args.fail_at(17, "material texture " + quote_word(args.word(17)) +
                         ": tessera has no textures; write 0 for none");
  }
  file.materials.push_back(add_material(args, std::move(material)));
}

void Importer::light(FileState&, const Args& args) {
  if (lights_.size() >= options_.limits.max_lights) {
    args.fail_command("more than " + std::to_string(options_.limits.max_lights) +
                      " lights (limit max_lights)");
  }
  const std::string_view kind = args.keyword();
  json light = {{"intensity", to_json(args.color(0, "color"))}};
  if (kind == "dir_light") {
    light["type"] = "directional";
    light["direction"] = to_json(args.direction(3, "direction"));
    lights_.push_back(std::move(light));
    return;
  }
  light["type"] = kind == "spot_light" ? "spot" : "point";
  light["position"] = to_json(args.vec3(3, "position"));
  const std::size_t at = kind == "spot_light" ? 9 : 6;
  if (kind == "spot_light") light["direction"] = to_json(args.direction(6, "direction"));
  const Vec3 attenuation{args.at_least_zero(at, "ca"), args.at_least_zero(at + 1, "la"),
                         args.at_least_zero(at + 2, "qa")};
  if (attenuation == Vec3(0.0))
    args.fail_at(at, std::string(kind) + " ca, la and qa must not all be 0 (infinitely bright)");
  light["attenuation"] = to_json(attenuation);
  if (kind == "spot_light") {
    // The course's angles are radians, and its cutoff is measured from the axis.
    const double cutoff = args.number(12, "sc");
    if (!(cutoff > 0.0 && cutoff <= std::numbers::pi / 2)) {
      args.fail_at(12,
                   "spot_light sc (the cone's half-angle, in radians) must be in (0, pi/2], "
                   "got " +
                       format_number(cutoff));
    }
    light["cutoff"] = std::min(90.0, cutoff * 180.0 / std::numbers::pi);
    light["exponent"] = args.at_least_zero(13, "sd");
  }
  lights_.push_back(std::move(light));
}

void Importer::camera(FileState&, const Args& args) {
  const Vec3 eye = args.vec3(0, "eye");
  const Vec3 towards = glm::normalize(unit(args.direction(3, "towards")));
  const Vec3 up = args.direction(6, "up");
  if (glm::length(glm::cross(towards, glm::normalize(unit(up)))) < min_up_sine)
    args.fail_at(6, "camera up must not be parallel to towards");
  // xfov is half the horizontal angle (the course's programs set the vertical half-angle
  // to atan(tan(xfov) * height / width) and gave OpenGL twice that).
  const double xfov = args.number(9, "xfov");
  if (!(xfov > 0.0 && xfov < std::numbers::pi / 2))
    args.fail_at(9,
                 "camera xfov (half the horizontal angle, in radians) must be in (0, pi/2), "
                 "got " +
                     format_number(xfov));
  args.number(10, "neardist");  // a ray tracer has no clipping planes
  args.number(11, "fardist");
  const double aspect = static_cast<double>(options_.height) / options_.width;
  const double fov_y = 2.0 * std::atan(std::tan(xfov) * aspect) * 180.0 / std::numbers::pi;
  const Vec3 look_at = eye + towards;
  if (!(fov_y > 0.0 && fov_y < 180.0) || look_at == eye || !std::isfinite(glm::length(look_at)))
    args.fail_command("camera cannot be written as tessera's: eye too far out, or xfov too wide");
  camera_ = json{
      {"eye", to_json(eye)}, {"look_at", to_json(look_at)}, {"up", to_json(up)}, {"fov_y", fov_y}};
}

void Importer::color_setting(FileState&, const Args& args) {
  (args.keyword() == "ambient" ? ambient_ : background_) = to_json(args.color(0, ""));
}

}  // namespace tessera::scn
