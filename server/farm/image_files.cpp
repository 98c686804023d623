#include "server/farm/image_files.hpp"

#include <stdexcept>

#include <system_error>

#include "common/image/image_io.hpp"
#include "server/farm/prune_files.hpp"

namespace tessera {

ImageFiles::ImageFiles(const std::filesystem::path& data_dir) : dir_(data_dir / "images") {
  std::filesystem::create_directories(dir_);
}

std::filesystem::path ImageFiles::path(const std::string& job_id) const {
  return dir_ / (job_id + ".exr");
}

void ImageFiles::write(const std::string& job_id, const Image& image) const {
  // RLE: the coordinator writes a file per frame, often on the cores its workers render
  // on, and ZIP took six times as long (ExrCompression).
  try {
    write_image(image, path(job_id), OutputTransfer::linear, ExrCompression::rle);
  } catch (const std::exception& e) {
    // The message becomes the job's error, which clients read: the file is named within
    // the data dir, not by the server's own path.
    std::string message = e.what();
    const std::string dir = dir_.string();
    for (std::size_t at; !dir.empty() && (at = message.find(dir)) != std::string::npos;)
      message.replace(at, dir.size(), "images");
    throw std::runtime_error(message);
  }
}

void ImageFiles::remove(const std::string& job_id) const {
  std::error_code ignored;
  std::filesystem::remove(path(job_id), ignored);
}

bool ImageFiles::has(const std::string& job_id) const {
  std::error_code ignored;
  return std::filesystem::is_regular_file(path(job_id), ignored);
}

void ImageFiles::prune(const std::function<bool(const std::string& job_id)>& keep) const {
  prune_files(dir_, ".exr", keep);
}

}  // namespace tessera
