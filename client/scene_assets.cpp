#include "client/scene_assets.hpp"

#include <unistd.h>

#include <cstdio>
#include <map>
#include <set>

#include "common/mesh_files/model_references.hpp"
#include "common/net/file_digest.hpp"
#include "common/protocol/asset_digest.hpp"
#include "common/scene/scene_parser.hpp"
#include "common/text/printable.hpp"

namespace tessera {
namespace {

std::string size_text(std::uint64_t bytes) {
  char text[32];
  if (bytes < 1024) return std::to_string(bytes) + " B";
  if (bytes < (1u << 20))
    std::snprintf(text, sizeof text, "%.1f KiB", static_cast<double>(bytes) / 1024);
  else
    std::snprintf(text, sizeof text, "%.1f MiB", static_cast<double>(bytes) / (1 << 20));
  return text;
}

std::string digest_of(const std::filesystem::path& path, const std::string& name) {
  const std::string digest = file_sha256(path);
  if (digest.empty()) throw SceneFileError(name, "", "cannot be read");
  return digest;
}

// An upload's progress: on a terminal, a bar redrawn in place as the pieces go out (ending
// each drawing with "erase to the end of the line", as the line may shrink); in a log or a
// pipe, one line when it starts.
class ProgressBar {
 public:
  ProgressBar(std::FILE* out, const std::string& name, std::uint64_t total)
      : out_(out), name_(printable(name)), terminal_(out != nullptr && ::isatty(::fileno(out))) {
    if (out_ != nullptr && !terminal_)
      std::fprintf(out_, "uploading %s (%s) ...\n", name_.c_str(), size_text(total).c_str());
    update(0, total);
  }
  ~ProgressBar() {
    if (terminal_) std::fputc('\n', out_);
  }
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void update(std::uint64_t sent, std::uint64_t total) {
    if (!terminal_) return;
    constexpr int kWidth = 30;
    const int percent = total == 0 ? 100 : static_cast<int>(sent * 100 / total);
    if (percent == shown_) return;
    shown_ = percent;
    const int filled = percent * kWidth / 100;
    std::fprintf(out_, "\ruploading %s [%s%s] %3d%% %s / %s\x1b[K", name_.c_str(),
                 std::string(filled, '#').c_str(), std::string(kWidth - filled, '-').c_str(),
                 percent, size_text(sent).c_str(), size_text(total).c_str());
    std::fflush(out_);
  }

 private:
  std::FILE* out_;
  std::string name_;
  bool terminal_;
  int shown_ = -1;
};

// Sends each file once, when the coordinator lacks it, streamed from disk.
class Sender {
 public:
  Sender(CoordinatorClient& api, std::FILE* progress) : api_(api), progress_(progress) {}

  void send(const std::filesystem::path& path, const std::string& name, const std::string& digest) {
    if (!seen_.insert(digest).second) return;
    if (api_.has_asset(digest)) {
      ++report_.held;
      return;
    }
    std::error_code error;
    const std::uint64_t size = std::filesystem::file_size(path, error);
    if (error) throw SceneFileError(name, "", "cannot be read: " + error.message());
    bool added = false;
    {
      ProgressBar bar(progress_, name, size);
      added = api_.put_asset_file(digest, path, [&bar](std::uint64_t sent, std::uint64_t total) {
        bar.update(sent, total);
      });
    }
    report_.bytes += size;
    if (added)
      ++report_.uploaded;
    else
      ++report_.held;  // arrived meanwhile, from another submission
  }
  const AssetUploads& report() const { return report_; }

 private:
  CoordinatorClient& api_;
  std::FILE* progress_;
  std::set<std::string> seen_;
  AssetUploads report_;
};

// A material's textures, {"texture": FILE, ...}, sent and named by digest instead:
// {"asset": DIGEST, "name": FILE, ...}.
void send_textures(nlohmann::json& material, const std::filesystem::path& folder, Sender& sender) {
  if (!material.is_object()) return;
  for (const std::string_view term : textured_term_names) {
    const auto found = material.find(term);
    if (found == material.end() || !found->is_object()) continue;
    nlohmann::json& texture = *found;
    if (!texture.contains("texture") || !texture["texture"].is_string()) continue;
    const std::string name = texture["texture"].get<std::string>();
    const std::filesystem::path path = folder / name;
    const std::string digest = digest_of(path, name);
    sender.send(path, name, digest);
    texture.erase("texture");
    texture["asset"] = protocol::AssetDigest::of_hex(digest).text();
    texture["name"] = name;
  }
}

}  // namespace

AssetUploads send_scene_assets(nlohmann::json& scene, const std::filesystem::path& folder,
                               CoordinatorClient& api, std::FILE* progress) {
  Sender sender(api, progress);
  if (const auto materials = scene.find("materials");
      materials != scene.end() && materials->is_object())
    for (auto& [name, material] : materials->items()) send_textures(material, folder, sender);
  const auto objects = scene.find("objects");
  if (objects == scene.end() || !objects->is_array()) return sender.report();
  for (nlohmann::json& object : *objects) {
    if (object.is_object() && object.contains("material"))
      send_textures(object["material"], folder, sender);
    if (!object.is_object() || object.value("type", "") != "mesh" || !object.contains("file") ||
        !object["file"].is_string())
      continue;
    const std::string name = object["file"].get<std::string>();
    const std::filesystem::path path = folder / name;
    // The scene was checked (parse_scene) before: the format is one of them.
    const std::optional<MeshFormat> named =
        object.contains("format") && object["format"].is_string()
            ? mesh_format_named(object["format"].get<std::string>())
            : mesh_format_of(name);
    const MeshFormat format = named.value_or(MeshFormat::obj);
    nlohmann::json files = nlohmann::json::object();
    for (const std::string& reference : model_references(path, format, name)) {
      const std::filesystem::path file = path.parent_path() / reference;
      const std::string digest = digest_of(file, reference);
      sender.send(file, reference, digest);
      files[reference] = protocol::AssetDigest::of_hex(digest).text();
    }
    const std::string digest = digest_of(path, name);
    sender.send(path, name, digest);
    object.erase("file");
    object["asset"] = protocol::AssetDigest::of_hex(digest).text();
    object["format"] = std::string(mesh_format_names[static_cast<int>(format)]);
    object["name"] = name;
    if (!files.empty()) object["files"] = std::move(files);
  }
  return sender.report();
}

}  // namespace tessera
