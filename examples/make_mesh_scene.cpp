// Writes examples' mesh scene: a (3,7) torus knot swept into a smooth tube of
// 1200 × 48 quads (115,200 triangles) over a checkered floor, with a mirror sphere.
// Usage: tessera_make_mesh_scene OUT.json
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <vector>

#include <nlohmann/json.hpp>

namespace {

using Vec = std::array<double, 3>;

Vec add(Vec a, Vec b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec sub(Vec a, Vec b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec scale(Vec a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(Vec a, Vec b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec cross(Vec a, Vec b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec normalize(Vec a) { return scale(a, 1.0 / std::sqrt(dot(a, a))); }

// Short decimals keep the file small; the shape does not need more.
double round5(double v) { return std::round(v * 1e5) / 1e5; }
nlohmann::json to_json(Vec v) { return {round5(v[0]), round5(v[1]), round5(v[2])}; }

// The knot's centre line, lying around the y axis at height 1.6.
Vec knot(double t) {
  constexpr double p = 3, q = 7;
  const double r = 1.0 + 0.42 * std::cos(q * t);
  return {r * std::cos(p * t), 1.6 + 0.42 * std::sin(q * t), r * std::sin(p * t)};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT.json\n", argv[0]);
    return 2;
  }
  constexpr int kAlong = 1200;
  constexpr int kAround = 48;
  constexpr double kTubeRadius = 0.16;
  constexpr double kTwoPi = 2.0 * std::numbers::pi;

  nlohmann::json positions = nlohmann::json::array();
  nlohmann::json normals = nlohmann::json::array();
  std::vector<Vec> points, centres;
  for (int i = 0; i < kAlong; ++i) {
    const double t = kTwoPi * i / kAlong;
    const Vec c = knot(t);
    const Vec tangent = normalize(sub(knot(t + 1e-4), knot(t - 1e-4)));
    // A frame from a fixed axis is smooth here: the tangent never points along y.
    const Vec side = normalize(cross(tangent, {0.0, 1.0, 0.0}));
    const Vec lift = cross(side, tangent);
    for (int j = 0; j < kAround; ++j) {
      const double a = kTwoPi * j / kAround;
      const Vec radial = add(scale(side, std::cos(a)), scale(lift, std::sin(a)));
      const Vec p = add(c, scale(radial, kTubeRadius));
      points.push_back(p);
      centres.push_back(c);
      positions.push_back(to_json(p));
      normals.push_back(to_json(radial));
    }
  }
  nlohmann::json triangles = nlohmann::json::array();
  auto index = [&](int i, int j) { return ((i % kAlong) * kAround) + (j % kAround); };
  auto emit = [&](int a, int b, int c) {
    // Keep the winding counter-clockwise seen from outside the tube.
    const Vec n = cross(sub(points[b], points[a]), sub(points[c], points[a]));
    if (dot(n, sub(points[a], centres[a])) < 0) std::swap(b, c);
    triangles.push_back({a, b, c});
  };
  for (int i = 0; i < kAlong; ++i)
    for (int j = 0; j < kAround; ++j) {
      emit(index(i, j), index(i + 1, j), index(i + 1, j + 1));
      emit(index(i, j), index(i + 1, j + 1), index(i, j + 1));
    }

  nlohmann::json scene = {
      {"version", 1},
      {"image", {{"width", 640}, {"height", 480}}},
      {"camera", {{"eye", {0.0, 3.2, 6.4}}, {"look_at", {0.0, 1.3, 0.0}}, {"fov_y", 42}}},
      {"render", {{"samples_per_pixel", 1}, {"max_depth", 4}}},
      {"background", {0.55, 0.65, 0.8}},
      {"ambient_light", 0.15},
      {"materials",
       {{"floor",
         {{"diffuse", 0.75}, {"checker", {{"size", 1.0}, {"diffuse", 0.2}, {"ambient", 0.05}}}}},
        {"gold",
         {{"ambient", {0.25, 0.2, 0.07}},
          {"diffuse", {0.75, 0.6, 0.22}},
          {"specular", {0.6, 0.55, 0.4}},
          {"shininess", 60},
          {"reflection", 0.2}}},
        {"mirror", {{"ambient", 0.0}, {"diffuse", 0.05}, {"specular", 0.9}, {"shininess", 200}}}}},
      {"lights",
       {{{"type", "point"}, {"position", {4.0, 7.0, 5.0}}, {"intensity", 0.8}},
        {{"type", "directional"}, {"direction", {-0.3, -1.0, -0.4}}, {"intensity", 0.35}}}},
      {"objects",
       {{{"type", "plane"},
         {"point", {0.0, 0.0, 0.0}},
         {"normal", {0.0, 1.0, 0.0}},
         {"material", "floor"}},
        {{"type", "sphere"},
         {"center", {-2.6, 0.8, -1.6}},
         {"radius", 0.8},
         {"material", "mirror"}},
        {{"type", "mesh"},
         {"positions", positions},
         {"normals", normals},
         {"triangles", triangles},
         {"material", "gold"}}}}};

  std::ofstream out(argv[1]);
  out << scene.dump() << '\n';
  if (!out) {
    std::fprintf(stderr, "cannot write %s\n", argv[1]);
    return 1;
  }
  std::printf("wrote %s: %zu triangles\n", argv[1], triangles.size());
  return 0;
}
