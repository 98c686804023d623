// Opens the image-file module (image_file_module.hpp says why there is one) once per process.
#pragma once

#include <mutex>
#include <thread>

#include "common/image_file_module.hpp"

namespace tessera {

// One per process, because what it holds is: a library mapped by the dynamic loader, which
// is never unmapped (OpenImageIO keeps state until exit).
class ImageFileLoader {
 public:
  static ImageFileLoader& instance();

  ImageFileLoader(const ImageFileLoader&) = delete;
  ImageFileLoader& operator=(const ImageFileLoader&) = delete;
  ~ImageFileLoader();

  // Starts opening the module on a thread of its own and returns at once, so that a program
  // that will write an image pays for the loading while it does other work. That work
  // should not itself call dlopen(), which waits for the load to finish. Throws at once
  // if the module's file is missing; another failure there is not reported: module()
  // tries again and throws.
  void start_in_background();

  // The module, opened on first use (waiting for a load already under way). Throws
  // std::runtime_error naming the file it looked for and the dynamic loader's reason.
  const ImageFileModule& module();

 private:
  ImageFileLoader() = default;
  void open();

  std::once_flag opened_;
  const ImageFileModule* module_ = nullptr;
  std::mutex background_mutex_;
  std::thread background_;
};

// ImageFileLoader::instance().module().
const ImageFileModule& image_files();

}  // namespace tessera
