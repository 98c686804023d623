// The finished images, beside the SQLite store: data_dir/images/JOB.exr (an animation's
// frames JOB.fN.exr), linear float, RLE-compressed,
// written once a job completes and sent as they are. Files only, no database state, so
// its calls may run beside the store's.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "common/image/image.hpp"

namespace tessera {

class ImageFiles {
 public:
  // Creates data_dir/images/ when it does not exist yet.
  explicit ImageFiles(const std::filesystem::path& data_dir);

  std::filesystem::path path(const std::string& job_id) const;
  const std::filesystem::path& dir() const { return dir_; }
  // Writes the job's file, atomically replaced: it appears whole or not at all.
  void write(const std::string& job_id, const Image& image) const;
  void remove(const std::string& job_id) const;
  bool has(const std::string& job_id) const;
  // Deletes image files (and leftovers of interrupted writes) whose job is not kept.
  void prune(const std::function<bool(const std::string& job_id)>& keep) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace tessera
