// Pruning the files of a data directory whose jobs are gone: the pixel files of the store
// and the image files, each named for its job.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace tessera {

// Deletes the files of `dir` named JOB`extension` whose job is not kept, and those whose
// name starts with a dot: write_image's temporary files, one left over being a crashed write.
void prune_files(const std::filesystem::path& dir, const char* extension,
                 const std::function<bool(const std::string& job_id)>& keep);

}  // namespace tessera
