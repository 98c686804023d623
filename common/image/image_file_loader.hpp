// Opens the image-file module (image_file_module.hpp says why there is one) once per process.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>

#include "common/image/image_file_module.hpp"

namespace tessera {

// One per process, because what it holds is: a library mapped by the dynamic loader, which
// is never unmapped (OpenImageIO keeps state until exit).
class ImageFileLoader {
 public:
  static ImageFileLoader& instance();

  ImageFileLoader(const ImageFileLoader&) = delete;
  ImageFileLoader& operator=(const ImageFileLoader&) = delete;

  // Runs `work` on a thread of its own while the calling thread opens the module, and
  // returns when both are done, rethrowing what `work` threw: a program that will write an
  // image pays for the loading while it does other work. That work should not itself call
  // dlopen(), which waits for the load to finish. Throws before starting anything if the
  // module's file is missing; another failure in opening it is not reported here: module()
  // tries again and throws.
  void open_during(const std::function<void()>& work);

  // The module, opened on first use (waiting for a load already under way). Throws
  // std::runtime_error naming the file it looked for and the dynamic loader's reason.
  const ImageFileModule& module();

  // Whether module() has succeeded, in any thread.
  bool opened() const { return opened_flag_.load(std::memory_order_acquire); }

 private:
  ImageFileLoader() = default;
  void open();

  std::once_flag opened_;
  const ImageFileModule* module_ = nullptr;
  std::atomic<bool> opened_flag_{false};
};

// ImageFileLoader::instance().module().
const ImageFileModule& image_files();

}  // namespace tessera
