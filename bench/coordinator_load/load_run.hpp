// One load run: N simulated workers park on a claim with no work (memory per idle worker),
// one job is submitted (accept time), and the workers claim and upload until it is done
// (tiles per second, claim latency, CPU), then the coordinator writes its image (peak
// memory).
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <boost/asio/ip/tcp.hpp>

namespace tessera::load {

struct LoadOptions {
  int workers = 1000;
  int width = 4096;
  int height = 4096;
  int tile_size = 16;
  int max_tiles = 256;
  int claim_wait_s = 20;
  int render_ms = 0;           // per lease, before its upload
  double timeout_s = 600;      // for the whole run, the image included
  bool wait_for_image = true;  // needs images_dir
  std::string api_token;
  std::string worker_token;
  bool json = false;  // the report as one JSON object
  // After the image file: GET /v1/jobs/{id}/image?format= each of these, timed, with the
  // coordinator's memory sampled meanwhile.
  std::vector<std::string> downloads;
};

struct ServerUnderTest {
  boost::asio::ip::tcp::endpoint endpoint;
  pid_t pid = 0;                     // 0: unknown, no /proc figures
  std::filesystem::path images_dir;  // "": unknown, the image is not waited for
};

// Runs the load and prints its report; returns the exit status (0: the job completed with
// no error).
int run_load(const LoadOptions& options, const ServerUnderTest& server);

}  // namespace tessera::load
