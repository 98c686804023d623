// What `tessera status`, `list`, `workers` and the progress of `submit --wait` and `watch`
// print: a job's status and health, tables of jobs and workers, progress lines, JSON.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/protocol/jobs.hpp"
#include "common/protocol/workers.hpp"

namespace tessera {

// 1:02:03 or 2:03.
std::string format_duration(double seconds);
void print_health(const protocol::JobHealth& health);
// `text` in at most `columns` characters, cut with "..." where longer.
std::string cut_to(const std::string& text, std::size_t columns);
void print_status(const protocol::JobStatus& job);
void print_job_table(const std::vector<protocol::JobStatus>& jobs);
void print_worker_table(const std::vector<protocol::Worker>& workers);
// What a job has done: its tiles, or for several frames the frames done and the tiles of
// the frame it finishes next (`frame_tiles`, when known).
std::string progress_count(const protocol::JobStatus& job,
                           const std::optional<protocol::JobStatus::Tiles>& frame_tiles);
// One line of progress; with `bar`, the drawn bar first.
std::string progress_line(const protocol::JobStatus& job, bool bar,
                          const std::optional<protocol::JobStatus::Tiles>& frame_tiles);
// ASCII only: a C1 control inside a string would reach the terminal raw otherwise.
void print_json(const nlohmann::json& body);

}  // namespace tessera
