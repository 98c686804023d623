#include "common/image/image_file_loader.hpp"

#include <dlfcn.h>

#include <filesystem>
#include <future>
#include <stdexcept>
#include <string>
#include <system_error>

namespace tessera {
namespace {

// The module sits at the same place relative to every program, in the build tree
// (build/client/tessera and build/lib/tessera/...) and when installed (bin/tessera and
// lib/tessera/...), so no path needs configuring.
std::filesystem::path module_path() {
  std::error_code error;
  const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) throw std::runtime_error("cannot find this program's own file: " + error.message());
  return (program.parent_path() / ".." / TESSERA_IMAGE_MODULE_DIR / TESSERA_IMAGE_MODULE_FILE)
      .lexically_normal();
}

std::string cannot_load(const std::string& reason) {
  return "cannot load image file support (" + reason +
         "): every program looks for it at ../" TESSERA_IMAGE_MODULE_DIR
         "/" TESSERA_IMAGE_MODULE_FILE " from its own directory";
}

}  // namespace

ImageFileLoader& ImageFileLoader::instance() {
  static ImageFileLoader loader;
  return loader;
}

void ImageFileLoader::open_during(const std::function<void()>& work) {
  // A missing module is found now rather than after a long render.
  const std::filesystem::path path = module_path();
  std::error_code error;
  if (!std::filesystem::exists(path, error))
    throw std::runtime_error(cannot_load(path.string() + ": no such file"));
  std::future<void> done = std::async(std::launch::async, work);
  try {
    module();
  } catch (const std::exception&) {
    // module() says why when it is called for an image.
  }
  done.get();
}

const ImageFileModule& ImageFileLoader::module() {
  std::call_once(opened_, [this] { open(); });  // a throw leaves it to be tried again
  return *module_;
}

void ImageFileLoader::open() {
  const std::filesystem::path path = module_path();
  void* handle = ::dlopen(path.c_str(), RTLD_LAZY | RTLD_LOCAL);
  if (handle == nullptr) throw std::runtime_error(cannot_load(::dlerror()));
  using Entry = const ImageFileModule* (*)();
  auto entry = reinterpret_cast<Entry>(::dlsym(handle, "tessera_image_file_module"));
  if (entry == nullptr)
    throw std::runtime_error("cannot load image file support: " + path.string() +
                             " has no tessera_image_file_module");
  module_ = entry();
  opened_flag_.store(true, std::memory_order_release);
}

const ImageFileModule& image_files() { return ImageFileLoader::instance().module(); }

}  // namespace tessera
