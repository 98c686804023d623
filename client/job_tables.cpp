#include "client/job_tables.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "client/human_time.hpp"
#include "client/short_ids.hpp"
#include "common/text/printable.hpp"

namespace tessera {

std::string format_duration(double seconds) {
  const long s = std::lround(seconds);
  char text[32];
  if (s >= 3600)
    std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  else
    std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
  return text;
}

// Signs of trouble the coordinator saw on a job, when there are any: a farm that renders
// the same tiles again, or delivers nothing, must not look like a slow one.
void print_health(const protocol::JobHealth& health) {
  std::string trouble;
  const auto add = [&](const std::string& sign) {
    trouble += (trouble.empty() ? "" : ", ") + sign;
  };
  const auto count = [&](int n, const char* one, const char* many) {
    if (n > 0) add(std::to_string(n) + " " + (n == 1 ? one : many));
  };
  count(health.tile_failures, "tile failure", "tile failures");
  count(health.refused_results, "result refused", "results refused");
  count(health.repeated_handouts, "tile sent out again", "tiles sent out again");
  // Half a minute without a tile while rendering is long for any tile size people use.
  if (health.no_progress_s >= 30)
    add("no tile delivered for " + format_duration(health.no_progress_s));
  if (trouble.empty()) return;
  std::printf("  trouble: %s\n", printable(trouble).c_str());
  if (health.last_problem)
    std::printf("  last problem: %s\n", printable(*health.last_problem).c_str());
}

// At most `columns` characters of `text` (whole UTF-8 sequences), the last one "…" when it
// was cut: a long name keeps a table's columns in line.
std::string cut_to(const std::string& text, std::size_t columns) {
  std::size_t characters = 0;
  for (std::size_t at = 0; at < text.size(); ++at) {
    if ((static_cast<unsigned char>(text[at]) & 0xc0) == 0x80) continue;  // inside a sequence
    if (++characters == columns) {
      std::size_t end = at + 1;
      while (end < text.size() && (static_cast<unsigned char>(text[end]) & 0xc0) == 0x80) ++end;
      return end >= text.size() ? text : text.substr(0, at) + "\u2026";
    }
  }
  return text;
}

// A job's state as people read it: a paused job whose leases are still out is "pausing",
// its workers finishing the tiles they hold.
static const char* state_words(const protocol::JobStatus& job) {
  if (job.state == JobState::paused && job.tiles.rendering > 0) return "pausing";
  return to_string(job.state);
}

void print_status(const protocol::JobStatus& job) {
  std::printf("%s  %-9s  %-20s  %3d%%  %d/%d tiles  priority %d  %dx%d\n",
              printable(job.id).c_str(), state_words(job), printable(job.name).c_str(),
              static_cast<int>(job.progress * 100), job.tiles.done, job.tiles.total, job.priority,
              job.width, job.height);
  if (job.frames.total > 1) {
    std::string frames = std::to_string(job.frames.done) + "/" + std::to_string(job.frames.total) +
                         " done of " + job.frames.list;
    if (job.frames.failed > 0) frames += ", failed " + job.frames.failed_list;
    if (job.frames.current) frames += ", next to finish " + std::to_string(*job.frames.current);
    std::printf("  frames: %s\n", printable(frames).c_str());
  }
  if (job.error) std::printf("  error: %s\n", printable(*job.error).c_str());
  print_health(job.health);
}

// One row per job under a header, the id cut to what tells it apart (any unique prefix
// works wherever a job id is asked for).
void print_job_table(const std::vector<protocol::JobStatus>& jobs) {
  const std::int64_t now = now_ms();
  std::printf("%-10s  %-20s  %-9s  %4s  %-13s  %4s  %-11s  %s\n", "ID", "NAME", "STATE", "DONE",
              "TILES", "PRIO", "SIZE", "SUBMITTED");
  for (const protocol::JobStatus& job : jobs) {
    const std::string tiles =
        std::to_string(job.tiles.done) + "/" + std::to_string(job.tiles.total);
    const std::string size = std::to_string(job.width) + "x" + std::to_string(job.height);
    // Padded by characters, not bytes, so that a name in another script stays in line.
    const std::string name = printable(cut_to(job.name, 20));
    std::size_t characters = 0;
    for (const char c : name) characters += (static_cast<unsigned char>(c) & 0xc0) != 0x80;
    std::printf("%-10s  %s%s  %-9s  %3d%%  %-13s  %4d  %-11s  %s\n",
                printable(short_id(job.id)).c_str(), name.c_str(),
                std::string(characters < 20 ? 20 - characters : 0, ' ').c_str(), state_words(job),
                static_cast<int>(job.progress * 100), tiles.c_str(), job.priority, size.c_str(),
                time_ago(job.created_at, now).c_str());
  }
}

void print_worker_table(const std::vector<protocol::Worker>& workers) {
  const std::int64_t now = now_ms();
  std::printf("%-14s  %-16s  %-15s  %-9s  %7s  %6s  %-10s  %s\n", "ID", "NAME", "HOST", "STATE",
              "THREADS", "TILES", "JOB", "LAST SEEN");
  for (const protocol::Worker& w : workers) {
    std::string state(protocol::name_in(protocol::kWorkerStateNames, w.state));
    if (w.draining) state += "*";  // draining: the footnote says so
    std::printf("%-14s  %-16s  %-15s  %-9s  %7d  %6llu  %-10s  %s\n", printable(w.id).c_str(),
                printable(w.name).c_str(), printable(w.host).c_str(), state.c_str(), w.threads,
                static_cast<unsigned long long>(w.tiles_rendered),
                printable(short_id(w.current_job.value_or("-"))).c_str(),
                time_ago(w.last_seen, now).c_str());
  }
  if (std::any_of(workers.begin(), workers.end(), [](const auto& w) { return w.draining; }))
    std::printf("* draining: takes no more tiles once its lease is done\n");
}

std::string progress_count(const protocol::JobStatus& job,
                           const std::optional<protocol::JobStatus::Tiles>& frame_tiles) {
  const auto of = [](int done, int total) {
    return std::to_string(done) + "/" + std::to_string(total);
  };
  if (job.frames.total <= 1) return of(job.tiles.done, job.tiles.total) + " tiles";
  std::string count = of(job.frames.done, job.frames.total) + " frames";
  if (job.frames.failed > 0) count += ", " + std::to_string(job.frames.failed) + " failed";
  if (job.frames.current && frame_tiles)
    count += " (frame " + std::to_string(*job.frames.current) + ": " +
             of(frame_tiles->done, frame_tiles->total) + " tiles)";
  return count;
}

std::string progress_line(const protocol::JobStatus& job, bool bar,
                          const std::optional<protocol::JobStatus::Tiles>& frame_tiles) {
  const std::string eta = job.eta_s ? format_duration(*job.eta_s) : "--:--";
  char text[256];
  std::string drawn;
  if (bar) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(job.progress * kWidth);
    drawn = "[" + std::string(filled, '#') + std::string(kWidth - filled, '.') + "] ";
  }
  std::snprintf(text, sizeof text, "%s%s %s %5.1f%%  elapsed %s  eta %s  %.2f Mrays/s",
                drawn.c_str(), to_string(job.state), progress_count(job, frame_tiles).c_str(),
                job.progress * 100, format_duration(job.elapsed_s).c_str(), eta.c_str(),
                job.stats.rays_per_s / 1e6);
  return text;
}

void print_json(const nlohmann::json& body) {
  std::printf("%s\n", body.dump(2, ' ', true).c_str());
}

}  // namespace tessera
