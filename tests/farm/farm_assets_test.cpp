// Scenes with mesh files on a real farm: the files travel once, as assets by digest, and
// the farm's image is the local render's, bit for bit; the asset routes check digests and
// refuse what they must.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <thread>

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include "common/net/coordinator_client.hpp"
#include "common/net/file_digest.hpp"
#include "examples/gltf_bytes.hpp"
#include "tests/farm/farm_fixture.hpp"
#include "tests/png_header_only.hpp"

namespace tessera::test {
namespace {

namespace fs = std::filesystem;

// A tetrahedron in a .gltf whose buffer is a .bin beside it.
void write_tetrahedron_gltf(const fs::path& dir) {
  std::string bin;
  for (const float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f})
    gltf_bytes::append(bin, v);
  for (const std::uint16_t i : {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}) gltf_bytes::append(bin, i);
  write_text(dir / "tetra.bin", bin);
  write_text(dir / "tetra.gltf", nlohmann::json::parse(R"({
    "asset": {"version": "2.0"},
    "nodes": [{"mesh": 0, "translation": [-1.6, 0.3, 0.5], "scale": [0.8, 0.8, 0.8]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
    "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.5, 0.9, 1],
                                            "metallicFactor": 0, "roughnessFactor": 0.3}}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
                  {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                    {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
    "buffers": [{"uri": "tetra.bin", "byteLength": 72}]
  })")
                                     .dump());
}

// A PNG whose texels vary in every channel, so that any texel read wrong shows.
void write_texture(const fs::path& path, int seed) {
  fs::create_directories(path.parent_path());
  Image image(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      float* p = image.pixel(x, y);
      p[0] = static_cast<float>((x * 7 + y * 3 + seed) % 16) / 15.0f;
      p[1] = static_cast<float>((x + y * 5 + 2 * seed) % 16) / 15.0f;
      p[2] = static_cast<float>((x * y + seed) % 16) / 15.0f;
    }
  write_image(image, path, OutputTransfer::srgb);
}

// examples/still_life.json's OBJ and MTL, a glTF with its .bin, and a textured OBJ (its
// MTL maps a PNG) on a floor with a PNG of its own, in one scene.
fs::path write_scene(const fs::path& dir) {
  fs::create_directories(dir / "models");
  const fs::path examples = fs::path(TESSERA_SOURCE_DIR) / "examples";
  fs::copy_file(examples / "models" / "still_life.obj", dir / "models" / "still_life.obj");
  fs::copy_file(examples / "models" / "still_life.mtl", dir / "models" / "still_life.mtl");
  write_tetrahedron_gltf(dir / "models");
  nlohmann::json scene = read_json_file(examples / "still_life.json");
  scene["image"] = {{"width", 96}, {"height", 72}};
  scene["render"] = {{"samples_per_pixel", 1}, {"max_depth", 6}, {"tile_size", 16}};
  scene["objects"].push_back({{"type", "mesh"}, {"file", "models/tetra.gltf"}});
  write_text(dir / "models" / "quad.obj",
             "mtllib quad.mtl\nv -1 0 0\nv 1 0 0\nv 1 2 0\nv -1 2 0\n"
             "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl painted\nf 1/1 2/2 3/3 4/4\n");
  write_text(dir / "models" / "quad.mtl", "newmtl painted\nKd 1 1 1\nmap_Kd tex/paint.png\n");
  write_texture(dir / "models" / "tex" / "paint.png", 1);
  write_texture(dir / "textures" / "floor.png", 5);
  scene["objects"].push_back({{"type", "mesh"},
                              {"file", "models/quad.obj"},
                              {"transform", {{{"translate", {-1.6, 0, -1.2}}}}}});
  scene["objects"][0]["material"] = {{"diffuse", {{"texture", "textures/floor.png"}}},
                                     {"specular", 0.1}};
  write_text(dir / "scene.json", scene.dump(2));
  return dir / "scene.json";
}

TEST(FarmAssetsTest, MeshFilesTravelOnceAndTheFarmRendersWhatTesseraRenderDoes) {
  Farm farm("farm-assets", 2);
  const fs::path scene = write_scene(farm.dir() / "project");
  const CliRun first = run_cli(
      farm.dir(),
      {"--server", farm.url(), "submit", scene.string(), "-o", (farm.dir() / "farm.exr").string()},
      std::chrono::seconds(120));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  // The OBJ, its MTL, the glTF and its .bin, the textured OBJ, its MTL and its PNG, and the
  // floor's PNG.
  EXPECT_TRUE(contains(first.output, "assets: 8 uploaded")) << first.output;
  const CliRun local = run_cli(farm.dir(), {"render", scene.string(), "-o",
                                            (farm.dir() / "local.exr").string(), "--threads", "2"});
  ASSERT_EQ(local.exit_code, 0) << local.output;
  EXPECT_TRUE(
      same_pixels(read_image(farm.dir() / "farm.exr"), read_image(farm.dir() / "local.exr")));

  // Again: nothing is sent twice, and the job still renders.
  const CliRun second = run_cli(
      farm.dir(),
      {"--server", farm.url(), "submit", scene.string(), "-o", (farm.dir() / "again.exr").string()},
      std::chrono::seconds(120));
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_TRUE(contains(second.output, "assets: 0 uploaded (0 bytes), 8 already on the coordinator"))
      << second.output;
  EXPECT_FALSE(contains(second.output, "uploading")) << second.output;
  EXPECT_TRUE(
      same_pixels(read_image(farm.dir() / "again.exr"), read_image(farm.dir() / "local.exr")));
}

std::string asset_target(const std::string& digest) { return "/v1/assets/sha256:" + digest; }

// A scene from elsewhere may name any file of the machine it is submitted from; only
// those in its folder (or under an --allow-path) are read and sent. Each other name is
// refused before a byte of it is read or anything is sent, naming the key.
TEST(FarmAssetsTest, SubmitSendsOnlyFilesInsideTheScenesFolder) {
  Farm farm("assets-confined", 0);
  const fs::path pack = farm.dir() / "pack";
  const fs::path elsewhere = farm.dir() / "private";
  write_texture(pack / "textures" / "ok.png", 1);
  write_texture(elsewhere / "secret.png", 2);
  fs::create_symlink(elsewhere / "secret.png", pack / "textures" / "link.png");
  fs::create_symlink(elsewhere, pack / "textures" / "dir");
  fs::copy_file(fs::path(TESSERA_SOURCE_DIR) / "examples" / "models" / "still_life.obj",
                elsewhere / "model.obj");
  fs::copy_file(fs::path(TESSERA_SOURCE_DIR) / "examples" / "models" / "still_life.mtl",
                elsewhere / "still_life.mtl");
  const nlohmann::json base = showcase(32, 24, 1, 16);
  const auto scene_with = [&](const std::string& key, const std::string& name) {
    nlohmann::json scene = base;
    if (key == "texture")
      scene["objects"][0]["material"] = {{"diffuse", {{"texture", name}}}};
    else
      scene["objects"].push_back({{"type", "mesh"}, {"file", name}});
    const fs::path file = pack / ("scene-" + std::to_string(scene.dump().size()) + ".json");
    write_text(file, scene.dump());
    return file;
  };
  const std::vector<std::pair<std::string, std::string>> refused{
      {"texture", "/etc/passwd"},           {"texture", (elsewhere / "secret.png").string()},
      {"texture", "../private/secret.png"}, {"texture", "textures/../../private/secret.png"},
      {"texture", "textures/link.png"},     {"texture", "textures/dir/secret.png"},
      {"file", "../private/model.obj"},     {"file", (elsewhere / "model.obj").string()},
  };
  for (const auto& [key, name] : refused) {
    const fs::path scene = scene_with(key, name);
    const CliRun run = run_cli(farm.dir(), {"--server", farm.url(), "submit", scene.string()});
    EXPECT_EQ(run.exit_code, 2) << name << ": " << run.output;
    EXPECT_NE(run.output.find("outside the scene's folder"), std::string::npos)
        << name << ": " << run.output;
    const std::string pointer =
        key == "texture" ? "/objects/0/material/diffuse/texture"
                         : "/objects/" + std::to_string(base["objects"].size()) + "/file";
    EXPECT_NE(run.output.find(pointer), std::string::npos) << name << ": " << run.output;
  }
  // Nothing reached the coordinator: no asset, no job, no request at all.
  EXPECT_TRUE(farm.api().jobs("", 10)["jobs"].empty());
  const auto stored_assets = [&] {
    int files = 0;
    if (fs::exists(farm.dir() / "data" / "assets"))
      for (const auto& entry : fs::recursive_directory_iterator(farm.dir() / "data" / "assets"))
        files += entry.is_regular_file();
    return files;
  };
  EXPECT_EQ(stored_assets(), 0);
  // Inside the folder, and under --allow-path, files go.
  const CliRun inside = run_cli(farm.dir(), {"--server", farm.url(), "submit",
                                             scene_with("texture", "textures/ok.png").string()});
  EXPECT_EQ(inside.exit_code, 0) << inside.output;
  const CliRun allowed =
      run_cli(farm.dir(), {"--server", farm.url(), "submit", "--allow-path", elsewhere.string(),
                           scene_with("texture", "../private/secret.png").string()});
  EXPECT_EQ(allowed.exit_code, 0) << allowed.output;
  EXPECT_EQ(farm.api().jobs("", 10)["jobs"].size(), 2u);
  EXPECT_EQ(stored_assets(), 2);
}

TEST(FarmAssetsTest, UploadsAreCheckedByDigestAndKeptOnlyWhole) {
  Farm farm("farm-asset-routes", 0, {"--max-asset-bytes", "4096"});
  HttpClient http = farm.http(std::chrono::seconds(10));
  const std::string bytes = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const std::string digest = bytes_sha256(bytes);
  const std::string other = bytes_sha256("something else");

  EXPECT_EQ(http.request("HEAD", asset_target(digest)).status, 404);
  const HttpResult wrong =
      http.request("PUT", asset_target(other), bytes, "application/octet-stream");
  EXPECT_EQ(wrong.status, 400);
  EXPECT_TRUE(contains(wrong.body, "digest_mismatch")) << wrong.body;
  EXPECT_EQ(http.request("HEAD", asset_target(other)).status, 404);

  EXPECT_EQ(http.request("PUT", asset_target(digest), bytes, "application/octet-stream").status,
            201);
  EXPECT_EQ(http.request("PUT", asset_target(digest), bytes, "application/octet-stream").status,
            200);
  EXPECT_EQ(http.request("HEAD", asset_target(digest)).status, 200);
  EXPECT_EQ(http.request("GET", asset_target(digest)).body, bytes);

  const std::string big(5000, 'x');
  const HttpResult over =
      http.request("PUT", asset_target(bytes_sha256(big)), big, "application/octet-stream");
  EXPECT_EQ(over.status, 413);
  EXPECT_EQ(http.request("PUT", "/v1/assets/sha256:ABC", bytes, "application/octet-stream").status,
            400);
  EXPECT_EQ(http.request("PUT", "/v1/assets/" + digest, bytes, "application/octet-stream").status,
            400);
  // Nothing of the refused uploads is left behind.
  EXPECT_TRUE(eventually([&] { return fs::is_empty(farm.dir() / "data" / "assets" / "incoming"); },
                         std::chrono::seconds(5)));
  EXPECT_FALSE(fs::exists(farm.dir() / "data" / "assets" / other));

  // A scene naming an asset the coordinator lacks: 422 at its pointer, naming the digest.
  const nlohmann::json missing = {{"scene",
                                   {{"image", {{"width", 8}, {"height", 8}}},
                                    {"camera", {{"eye", {0, 0, 5}}, {"look_at", {0, 0, 0}}}},
                                    {"objects",
                                     {{{"type", "mesh"},
                                       {"asset", "sha256:" + digest},
                                       {"format", "obj"},
                                       {"files", {{"x.mtl", "sha256:" + other}}}}}}}}};
  const HttpResult refused = http.request("POST", "/v1/jobs", missing.dump());
  EXPECT_EQ(refused.status, 422);
  EXPECT_TRUE(contains(refused.body, "\"path\":\"/scene/objects/0/files/x.mtl\"")) << refused.body;
  EXPECT_TRUE(contains(refused.body, other)) << refused.body;

  // A texture the coordinator holds but no worker could decode: refused at submit, naming
  // it, and a texture it lacks: 422 at the texture's pointer.
  EXPECT_EQ(http.request("PUT", asset_target(digest), bytes, "application/octet-stream").status,
            200);
  const auto textured = [&](const std::string& texture_digest) {
    return nlohmann::json{
        {"scene",
         {{"image", {{"width", 8}, {"height", 8}}},
          {"camera", {{"eye", {0, 0, 5}}, {"look_at", {0, 0, 0}}}},
          {"objects",
           {{{"type", "sphere"},
             {"center", {0, 0, 0}},
             {"radius", 1},
             {"material",
              {{"diffuse", {{"asset", "sha256:" + texture_digest}, {"name", "paint.png"}}}}}}}}}}};
  };
  const HttpResult undecodable = http.request("POST", "/v1/jobs", textured(digest).dump());
  EXPECT_EQ(undecodable.status, 400) << undecodable.body;
  EXPECT_TRUE(contains(undecodable.body, "texture paint.png")) << undecodable.body;
  const HttpResult absent = http.request("POST", "/v1/jobs", textured(other).dump());
  EXPECT_EQ(absent.status, 422);
  EXPECT_TRUE(contains(absent.body, "\"path\":\"/scene/objects/0/material/diffuse/asset\""))
      << absent.body;
  // Textures whose headers claim more pixels together than a scene's may have: refused at
  // submit from their headers, before any worker could spend memory decoding them.
  nlohmann::json heavy = textured(digest);
  heavy["scene"]["objects"] = nlohmann::json::array();
  for (std::uint32_t i = 0; i < 5; ++i) {
    const std::string png = png_header_only(8192 - i, 8192 - i);  // five distinct files
    const std::string png_digest = bytes_sha256(png);
    ASSERT_EQ(http.request("PUT", asset_target(png_digest), png, "application/octet-stream").status,
              201);
    nlohmann::json sphere = textured(png_digest)["scene"]["objects"][0];
    sphere["center"] = {static_cast<int>(i), 0, 0};
    heavy["scene"]["objects"].push_back(sphere);
  }
  const HttpResult too_many = http.request("POST", "/v1/jobs", heavy.dump());
  EXPECT_EQ(too_many.status, 400) << too_many.body;
  EXPECT_TRUE(contains(too_many.body, "pixels together")) << too_many.body;
  EXPECT_EQ(http.request("GET", "/healthz").status, 200);
}

TEST(FarmAssetsTest, AFileUploadsStreamedFromDiskAPieceAtATime) {
  Farm farm("farm-asset-file", 0);
  // 24 MiB of varied bytes: many pieces for the socket.
  std::string bytes(24u << 20, '\0');
  for (std::size_t i = 0; i < bytes.size(); ++i)
    bytes[i] = static_cast<char>((i * 2654435761u) >> 13);
  const fs::path file = farm.dir() / "big.bin";
  write_text(file, bytes);
  const std::string digest = bytes_sha256(bytes);
  CoordinatorClient client(farm.url(), "", std::chrono::seconds(30));
  std::vector<std::uint64_t> sent;
  std::uint64_t announced = 0;
  EXPECT_TRUE(client.put_asset_file(digest, file, [&](std::uint64_t done, std::uint64_t total) {
    sent.push_back(done);
    announced = total;
  }));
  EXPECT_EQ(announced, bytes.size());
  ASSERT_GT(sent.size(), 2u) << "the body went out in one piece";
  EXPECT_TRUE(std::is_sorted(sent.begin(), sent.end()));
  EXPECT_EQ(sent.back(), bytes.size());
  EXPECT_EQ(file_sha256(farm.dir() / "data" / "assets" / digest), digest);
  // Again: held already.
  EXPECT_FALSE(client.put_asset_file(digest, file));
}

TEST(FarmAssetsTest, OnATerminalSubmitDrawsAnUploadsProgressBar) {
  if (!fs::exists("/usr/bin/script"))
    GTEST_SKIP() << "needs script(1) (Debian's bsdutils) to give the CLI a terminal";
  Farm farm("farm-asset-bar", 0);
  const fs::path project = farm.dir() / "project";
  fs::create_directories(project / "models");
  // An OBJ of one triangle after 8 MiB of comment: many pieces to draw.
  write_text(project / "models" / "big.obj",
             "# " + std::string(8u << 20, 'x') + "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  write_text(project / "scene.json",
             R"({"image": {"width": 8, "height": 8},
                 "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]},
                 "objects": [{"type": "mesh", "file": "models/big.obj"}]})");
  const std::string command = std::string(TESSERA_CLI_BIN) + " --server " + farm.url() +
                              " submit " + (project / "scene.json").string();
  const fs::path log = farm.dir() / "terminal.log";
  {
    Process terminal("/usr/bin/script", {"-qec", command, "/dev/null"}, log);
    const auto status = terminal.wait_for(std::chrono::seconds(60));
    ASSERT_TRUE(status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << read_text(log);
  }
  const std::string shown = read_text(log);
  // Redrawn in place as the pieces go out, ending full.
  EXPECT_TRUE(contains(shown, "\ruploading models/big.obj [")) << shown;
  EXPECT_TRUE(contains(shown, "[##############################] 100% 8.0 MiB / 8.0 MiB")) << shown;
  EXPECT_TRUE(contains(shown, "%") && contains(shown, "[###")) << shown;
}

TEST(FarmAssetsTest, UploadsOfOneDigestAtOnceAllSucceedAndMakeOneFile) {
  Farm farm("farm-asset-race", 0);
  const std::string bytes(300000, 'q');
  const std::string digest = bytes_sha256(bytes);
  std::atomic<int> added{0}, held{0}, other{0};
  std::vector<std::thread> threads;
  for (int i = 0; i < 6; ++i)
    threads.emplace_back([&] {
      HttpClient http = farm.http(std::chrono::seconds(20));
      const int status =
          http.request("PUT", asset_target(digest), bytes, "application/octet-stream").status;
      (status == 201 ? added : status == 200 ? held : other)++;
    });
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(added.load(), 1);
  EXPECT_EQ(held.load(), 5);
  EXPECT_EQ(other.load(), 0);
  EXPECT_EQ(read_text(farm.dir() / "data" / "assets" / digest), bytes);
}

TEST(FarmAssetsTest, AWorkerFetchesACorruptCacheEntryAgain) {
  Farm farm("farm-asset-cache", 0);
  const fs::path scene = write_scene(farm.dir() / "project");
  const fs::path cache = farm.dir() / "cache";
  Process worker(TESSERA_WORKER_BIN,
                 {"--server", farm.url(), "--threads", "2", "--name", "cached", "--asset-cache",
                  cache.string()},
                 farm.dir() / "cached.log");
  const CliRun first = run_cli(
      farm.dir(),
      {"--server", farm.url(), "submit", scene.string(), "-o", (farm.dir() / "first.exr").string()},
      std::chrono::seconds(120));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const std::string obj_digest = file_sha256(farm.dir() / "project" / "models" / "still_life.obj");
  ASSERT_TRUE(fs::exists(cache / obj_digest));
  write_text(cache / obj_digest, "v 0 0 0\n");  // corrupt: another digest

  // Another scene (another job) naming the same assets: the entry is fetched again.
  nlohmann::json changed = read_json_file(scene);
  changed["background"] = {0.1, 0.1, 0.1};
  write_text(scene, changed.dump());
  const CliRun second = run_cli(farm.dir(),
                                {"--server", farm.url(), "submit", scene.string(), "-o",
                                 (farm.dir() / "second.exr").string()},
                                std::chrono::seconds(120));
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_EQ(file_sha256(cache / obj_digest), obj_digest);
  const CliRun local =
      run_cli(farm.dir(), {"render", scene.string(), "-o", (farm.dir() / "local.exr").string()});
  ASSERT_EQ(local.exit_code, 0) << local.output;
  EXPECT_TRUE(
      same_pixels(read_image(farm.dir() / "second.exr"), read_image(farm.dir() / "local.exr")));
}

TEST(FarmAssetsTest, CollectionRemovesOldAssetsButNeverOneAQueuedJobNeeds) {
  // Assets not named for a second go; with no worker, the job stays queued meanwhile.
  Farm farm("farm-asset-collection", 0, {"--asset-retention", "1"});
  const fs::path scene = write_scene(farm.dir() / "project");
  HttpClient http = farm.http(std::chrono::seconds(10));
  const std::string unused = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  ASSERT_EQ(
      http.request("PUT", asset_target(bytes_sha256(unused)), unused, "application/octet-stream")
          .status,
      201);
  const CliRun submitted =
      run_cli(farm.dir(), {"--server", farm.url(), "--json", "submit", scene.string()});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  const std::string obj = file_sha256(farm.dir() / "project" / "models" / "still_life.obj");
  const std::string bin = file_sha256(farm.dir() / "project" / "models" / "tetra.bin");
  const fs::path assets = farm.dir() / "data" / "assets";
  ASSERT_TRUE(eventually([&] { return !fs::exists(assets / bytes_sha256(unused)); },
                         std::chrono::seconds(20)))
      << "an asset no job names was never removed";
  // Three more passes (one a second) later, the queued job's assets are all still there:
  // what must not happen has no condition to wait for, only a window to watch.
  std::this_thread::sleep_for(std::chrono::seconds(3));
  EXPECT_TRUE(fs::exists(assets / obj));
  EXPECT_TRUE(fs::exists(assets / bin));

  // A worker renders the job from them.
  Process worker(TESSERA_WORKER_BIN,
                 {"--server", farm.url(), "--threads", "2", "--name", "late", "--asset-cache",
                  (farm.dir() / "cache").string()},
                 farm.dir() / "late.log");
  const nlohmann::json jobs = farm.api().jobs("queued", 10);
  ASSERT_EQ(jobs["jobs"].size(), 1u);
  EXPECT_EQ(farm.wait_finished(jobs["jobs"][0]["id"])["state"], "completed");
  // Once no job needs them, they go too.
  EXPECT_TRUE(eventually([&] { return !fs::exists(assets / obj); }, std::chrono::seconds(20)));
}

TEST(FarmAssetsTest, ADiskThatFillsMidUploadLeavesNoPartialAssetAndTheServerKeepsServing) {
  const fs::path dir = fresh_dir("farm-asset-disk-full");
  const fs::path data = dir / "data";
  // A 4 MiB file system for the data dir.
  const SmallDisk disk(data, "4m");
  if (!disk.mounted())
    GTEST_SKIP() << "needs root to mount a small tmpfs for the data dir (CI runs as root); see "
                 << (dir / "mount.log");
  Process server(TESSERA_SERVER_BIN,
                 {"--listen", "127.0.0.1:0", "--data-dir", data.string(), "--local-workers", "0",
                  "--port-file", (dir / "port").string(), "--log-level", "warn"},
                 dir / "server.log");
  ASSERT_TRUE(eventually([&] { return fs::exists(dir / "port"); }, std::chrono::seconds(20)))
      << read_text(dir / "server.log");
  int port = 0;
  std::ifstream(dir / "port") >> port;
  HttpClient http("http://127.0.0.1:" + std::to_string(port), std::chrono::seconds(20));

  const std::string big(6 << 20, 'b');  // more than the disk holds
  const HttpResult full =
      http.request("PUT", asset_target(bytes_sha256(big)), big, "application/octet-stream");
  EXPECT_EQ(full.status, 507) << full.body;
  EXPECT_TRUE(eventually([&] { return fs::is_empty(data / "assets" / "incoming"); },
                         std::chrono::seconds(10)));
  EXPECT_FALSE(fs::exists(data / "assets" / bytes_sha256(big)));
  // The space came back: a small asset still goes in, and the server answers as before.
  HttpClient again("http://127.0.0.1:" + std::to_string(port), std::chrono::seconds(20));
  const std::string small = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(
      again.request("PUT", asset_target(bytes_sha256(small)), small, "application/octet-stream")
          .status,
      201);
  EXPECT_EQ(again.request("GET", "/healthz").status, 200);
  EXPECT_FALSE(server.wait_for(std::chrono::milliseconds(0)).has_value()) << "the server died";
}

}  // namespace
}  // namespace tessera::test
