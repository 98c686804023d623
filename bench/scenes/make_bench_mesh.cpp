// Writes the benchmark's big mesh scene in both formats: OUT_DIR/mesh.json (Tessera, compact
// JSON) and OUT_DIR/mesh.pov (POV-Ray 3.7, one mesh2). The two describe the same scene with
// the conventions of bench/scenes/README.md, so both renderers compute the same image.
//
// The mesh is a rippled torus, tilted towards the camera and resting on a checkered,
// slightly reflective floor, with smooth (area-weighted) vertex normals:
// ALONG x AROUND quads, two triangles each; the default 1024 x 512 gives 1,048,576 triangles.
//
// Usage: tessera_make_bench_mesh OUT_DIR [ALONG AROUND]
#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace {

using Vec = glm::dvec3;

// ---- The scene, shared by both writers. ----------------------------------------------------

constexpr double kMajorRadius = 1.45;
constexpr double kTubeRadius = 0.5;
constexpr double kTiltDegrees = 32.0;  // about the x axis, top towards the camera
constexpr double kRestHeight = 0.002;  // gap between the torus's lowest point and the floor
constexpr int kMaxDepth = 3;
constexpr double kFovY = 36.0;

const Vec kEye = {0.0, 3.3, 7.2};
const Vec kLookAt = {0.0, 0.7, 0.0};
const Vec kBackground = {0.3, 0.42, 0.62};
const Vec kAmbientLight = {0.12, 0.12, 0.12};

struct Light {
  Vec position;
  Vec intensity;
};
const Light kLights[] = {
    {{-4.0, 6.5, 4.5}, {0.75, 0.72, 0.68}},
    {{5.0, 3.5, 2.0}, {0.3, 0.33, 0.4}},
};

// Floor: a checker of size 1 (Tessera's cell row y in [-1, 0) under y = 0), reflection 0.15.
const Vec kFloorA = {0.8, 0.8, 0.76};
const Vec kFloorB = {0.16, 0.2, 0.3};
constexpr double kFloorReflection = 0.15;
// Torus: ambient = diffuse (POV-Ray: ambient 1 with the pigment = K_D), phong, no reflection.
const Vec kCopper = {0.72, 0.36, 0.2};
constexpr double kCopperSpecular = 0.6;
constexpr double kCopperShininess = 40;

struct Mesh {
  std::vector<Vec> positions;
  std::vector<Vec> normals;
  std::vector<std::array<int, 3>> triangles;
};

// The tube's radius, rippled along and around.
double tube_radius(double u, double v) {
  return kTubeRadius * (1.0 + 0.07 * std::sin(9.0 * u) * std::cos(6.0 * v) +
                        0.025 * std::sin(31.0 * u + 3.0 * v));
}

Mesh make_torus(int along, int around) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  const double tilt = kTiltDegrees * std::numbers::pi / 180.0;
  const double ct = std::cos(tilt), st = std::sin(tilt);
  Mesh mesh;
  mesh.positions.reserve(static_cast<size_t>(along) * around);
  for (int i = 0; i < along; ++i) {
    const double u = kTwoPi * i / along;
    const Vec out = {std::cos(u), 0.0, std::sin(u)};
    for (int j = 0; j < around; ++j) {
      const double v = kTwoPi * j / around;
      const Vec radial = out * std::cos(v) + Vec(0.0, std::sin(v), 0.0);
      const Vec p = out * kMajorRadius + radial * tube_radius(u, v);
      // Tilt about x: +y leans towards +z (the camera).
      mesh.positions.push_back({p[0], p[1] * ct - p[2] * st, p[1] * st + p[2] * ct});
    }
  }
  double lowest = mesh.positions[0][1];
  for (const Vec& p : mesh.positions) lowest = std::min(lowest, p[1]);
  for (Vec& p : mesh.positions) p[1] += kRestHeight - lowest;

  auto index = [&](int i, int j) { return (i % along) * around + (j % around); };
  mesh.triangles.reserve(2 * static_cast<size_t>(along) * around);
  for (int i = 0; i < along; ++i)
    for (int j = 0; j < around; ++j) {
      // Counter-clockwise seen from outside: (u, v) -> (u, v+1) -> (u+1, v+1).
      const int a = index(i, j), b = index(i, j + 1), c = index(i + 1, j + 1), d = index(i + 1, j);
      mesh.triangles.push_back({a, b, c});
      mesh.triangles.push_back({a, c, d});
    }

  // Area-weighted vertex normals.
  mesh.normals.assign(mesh.positions.size(), Vec{0.0, 0.0, 0.0});
  for (const auto& t : mesh.triangles) {
    const Vec& p0 = mesh.positions[t[0]];
    const Vec n = glm::cross(mesh.positions[t[1]] - p0, mesh.positions[t[2]] - p0);
    for (int k : t) mesh.normals[k] += n;
  }
  for (Vec& n : mesh.normals) n = glm::normalize(n);
  return mesh;
}

// ---- Writers. ------------------------------------------------------------------------------

// Five decimals keep the files small: both renderers read the same decimal values, and a
// triangle's edges (about 0.006) stay far above the rounding.
constexpr const char* kPos = "%.5f";

struct File {
  std::FILE* f = nullptr;
  std::vector<char> buffer = std::vector<char>(1 << 22);
  explicit File(const std::string& path) : f(std::fopen(path.c_str(), "wb")) {
    if (f == nullptr) {
      std::fprintf(stderr, "cannot write %s: %s\n", path.c_str(), std::strerror(errno));
      std::exit(1);
    }
    std::setvbuf(f, buffer.data(), _IOFBF, buffer.size());
  }
  ~File() {
    if (f != nullptr && std::fclose(f) != 0) {
      std::fprintf(stderr, "write failed: %s\n", std::strerror(errno));
      std::exit(1);
    }
  }
};

void json_vec(std::FILE* f, const Vec& v) { std::fprintf(f, "[%.9g,%.9g,%.9g]", v[0], v[1], v[2]); }
void json_vec5(std::FILE* f, const Vec& v) {
  std::fprintf(f, "[%.5f,%.5f,%.5f]", v[0], v[1], v[2]);
}

// Every material here has K_A = K_D (see README.md): both keys get the same colour.
void json_ambient_diffuse(std::FILE* f, const Vec& colour) {
  std::fprintf(f, "\"ambient\":");
  json_vec(f, colour);
  std::fprintf(f, ",\"diffuse\":");
  json_vec(f, colour);
}

void json_vec5_list(std::FILE* f, const std::vector<Vec>& list) {
  for (size_t k = 0; k < list.size(); ++k) {
    if (k != 0) std::fputc(',', f);
    json_vec5(f, list[k]);
  }
}

void write_json(const std::string& path, const Mesh& mesh) {
  File out(path);
  std::FILE* f = out.f;
  std::fprintf(f, "{\"version\":1,\"image\":{\"width\":1920,\"height\":1080},");
  std::fprintf(f, "\"camera\":{\"eye\":");
  json_vec(f, kEye);
  std::fprintf(f, ",\"look_at\":");
  json_vec(f, kLookAt);
  std::fprintf(f, ",\"up\":[0,1,0],\"fov_y\":%.9g},", kFovY);
  std::fprintf(f,
               "\"render\":{\"samples_per_pixel\":1,\"max_depth\":%d,\"tile_size\":32,"
               "\"output_transfer\":\"srgb\"},",
               kMaxDepth);
  std::fprintf(f, "\"background\":");
  json_vec(f, kBackground);
  std::fprintf(f, ",\"ambient_light\":");
  json_vec(f, kAmbientLight);
  std::fprintf(f, ",\"materials\":{\"floor\":{");
  json_ambient_diffuse(f, kFloorA);
  std::fprintf(f, ",\"specular\":0,\"reflection\":%.9g,\"checker\":{\"size\":1,", kFloorReflection);
  json_ambient_diffuse(f, kFloorB);
  std::fprintf(f, "}},\"copper\":{");
  json_ambient_diffuse(f, kCopper);
  std::fprintf(f, ",\"specular\":%.9g,\"shininess\":%.9g,\"reflection\":0}},", kCopperSpecular,
               kCopperShininess);
  std::fprintf(f, "\"lights\":[");
  bool first = true;
  for (const Light& light : kLights) {
    std::fprintf(f, "%s{\"type\":\"point\",\"position\":", first ? "" : ",");
    json_vec(f, light.position);
    std::fprintf(f, ",\"intensity\":");
    json_vec(f, light.intensity);
    std::fprintf(f, ",\"attenuation\":[1,0,0]}");
    first = false;
  }
  std::fprintf(f,
               "],\"objects\":[{\"type\":\"plane\",\"point\":[0,0,0],\"normal\":[0,1,0],"
               "\"material\":\"floor\"},\n{\"type\":\"mesh\",\"material\":\"copper\",\n"
               "\"positions\":[");
  json_vec5_list(f, mesh.positions);
  std::fprintf(f, "],\n\"normals\":[");
  json_vec5_list(f, mesh.normals);
  std::fprintf(f, "],\n\"triangles\":[");
  for (size_t k = 0; k < mesh.triangles.size(); ++k) {
    const auto& t = mesh.triangles[k];
    std::fprintf(f, "%s[%d,%d,%d]", k != 0 ? "," : "", t[0], t[1], t[2]);
  }
  std::fprintf(f, "]}]}\n");
}

void pov_vec(std::FILE* f, const Vec& v) {
  std::fprintf(f, "<%.9g, %.9g, %.9g>", v[0], v[1], v[2]);
}

void write_pov(const std::string& path, const Mesh& mesh) {
  File out(path);
  std::FILE* f = out.f;
  std::fprintf(f,
               "// Tessera benchmark scene \"mesh\" in POV-Ray 3.7 SDL; the twin of mesh.json.\n"
               "// Generated by bench/scenes/make_bench_mesh.cpp: %zu triangles.\n"
               "// Coordinates are Tessera's (right-handed, +y up); \"right -x*...\" flips the\n"
               "// image horizontally so that POV-Ray's left-handed camera frames it identically.\n"
               "// See bench/scenes/README.md for the conventions and the command lines.\n"
               "#version 3.7;\n\n"
               "#declare MaxDepth = %d;\n#declare FovY = %.9g;\n\n"
               "global_settings {\n  assumed_gamma 1.0\n  adc_bailout 0\n"
               "  max_trace_level MaxDepth + 1\n  ambient_light rgb ",
               mesh.triangles.size(), kMaxDepth, kFovY);
  pov_vec(f, kAmbientLight);
  std::fprintf(f, "\n}\n\ncamera {\n  perspective\n  location ");
  pov_vec(f, kEye);
  std::fprintf(f, "\n  look_at ");
  pov_vec(f, kLookAt);
  std::fprintf(f,
               "\n  sky y\n  up y\n  right -x * image_width / image_height\n"
               "  angle 2 * degrees(atan(tan(radians(FovY / 2)) * image_width / image_height))\n"
               "}\n\nbackground { rgb ");
  pov_vec(f, kBackground);
  std::fprintf(f, " }\n\n");
  for (const Light& light : kLights) {
    std::fprintf(f, "light_source { ");
    pov_vec(f, light.position);
    std::fprintf(f, " rgb ");
    pov_vec(f, light.intensity);
    std::fprintf(f, " }\n");
  }
  std::fprintf(f,
               "\n// Checker of size 1: lifted half a cell so that POV-Ray samples the cell row\n"
               "// y in [-1, 0) like Tessera does under y = 0.\n"
               "plane {\n  y, 0\n  texture {\n    checker\n");
  for (const Vec& c : {kFloorA, kFloorB}) {
    std::fprintf(f, "      texture { pigment { rgb ");
    pov_vec(f, c);
    std::fprintf(f, " } finish { ambient 1 diffuse 1 reflection { %.9g } } }\n", kFloorReflection);
  }
  std::fprintf(f, "    translate <0, 0.5, 0>\n  }\n}\n\nmesh2 {\n  vertex_vectors {\n    %zu",
               mesh.positions.size());
  for (const Vec& p : mesh.positions) std::fprintf(f, ",\n<%.5f,%.5f,%.5f>", p[0], p[1], p[2]);
  std::fprintf(f, "\n  }\n  normal_vectors {\n    %zu", mesh.normals.size());
  for (const Vec& n : mesh.normals) std::fprintf(f, ",\n<%.5f,%.5f,%.5f>", n[0], n[1], n[2]);
  std::fprintf(f, "\n  }\n  face_indices {\n    %zu", mesh.triangles.size());
  for (const auto& t : mesh.triangles) std::fprintf(f, ",\n<%d,%d,%d>", t[0], t[1], t[2]);
  std::fprintf(f, "\n  }\n  texture {\n    pigment { rgb ");
  pov_vec(f, kCopper);
  std::fprintf(f, " }\n    finish { ambient 1 diffuse 1 phong %.9g phong_size %.9g }\n  }\n}\n",
               kCopperSpecular, kCopperShininess);
}

int parse_count(const char* text) {
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || value < 3 || value > 16384) {
    std::fprintf(stderr, "bad count %s (3 to 16384)\n", text);
    std::exit(2);
  }
  return static_cast<int>(value);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && argc != 4) {
    std::fprintf(stderr, "usage: %s OUT_DIR [ALONG AROUND]   (default 1024 512)\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  const int along = argc == 4 ? parse_count(argv[2]) : 1024;
  const int around = argc == 4 ? parse_count(argv[3]) : 512;
  const Mesh mesh = make_torus(along, around);
  write_json(dir + "/mesh.json", mesh);
  write_pov(dir + "/mesh.pov", mesh);
  std::printf("wrote %s/mesh.json and %s/mesh.pov: %zu vertices, %zu triangles\n", dir.c_str(),
              dir.c_str(), mesh.positions.size(), mesh.triangles.size());
  return 0;
}
