#include "client/job_follow.hpp"

#include <chrono>
#include <cstdio>
#include <thread>

#include "client/command_failure.hpp"
#include "common/protocol/events.hpp"
#include "common/protocol/paths.hpp"
#include "common/text/printable.hpp"

namespace tessera {

protocol::JobStatus poll_until_finished(CoordinatorClient& api, const std::string& id,
                                        ProgressPrinter& printer, const OnUpdate& on_update) {
  while (true) {
    const protocol::JobStatus job = api.job(id, 0.5);
    printer.show(job);
    if (on_update) on_update(job);
    if (is_finished(job.state)) return job;
  }
}

protocol::JobStatus watch(CoordinatorClient& api, const std::string& id, ProgressPrinter& printer,
                          const OnUpdate& on_update) {
  protocol::JobStatus job;
  bool finished = false;
  std::optional<std::string> last_event;
  const auto update = [&](protocol::JobStatus now) {
    job = std::move(now);
    printer.show(job);
    if (on_update) on_update(job);
    finished = is_finished(job.state);
  };
  for (int breaks = 0; !finished;) {
    bool opened = false;
    try {
      api.events(
          std::string(protocol::route::events), last_event,
          [&] {
            opened = true;
            update(api.job(id));
            return !finished;
          },
          [&](const ServerEvent& event) {
            if (!event.id.empty()) last_event = event.id;
            if (finished) return false;
            if (event.type == protocol::event::resync) {
              update(api.job(id));
            } else if (event.type == protocol::event::job) {
              const auto data = nlohmann::json::parse(event.data, nullptr, false);
              if (!data.is_object() || data.value("id", "") != id) return true;
              update(protocol::JobStatus::read(protocol::FieldReader(data)));
            } else if (event.type == protocol::event::job_removed) {
              const auto data = nlohmann::json::parse(event.data, nullptr, false);
              if (!data.is_object()) return true;
              if (protocol::JobRemoved::read(protocol::FieldReader(data)).id == id)
                fail(kExitJobFailed, "job " + id + " was removed");
            }
            return !finished;
          });
      // A stream that ended before it opened came from no coordinator that has events.
      if (!opened) return poll_until_finished(api, id, printer, on_update);
    } catch (const ApiError& e) {
      if (e.status() != 404) throw;
      return poll_until_finished(api, id, printer, on_update);  // a coordinator without events
    } catch (const HttpError&) {
      // The coordinator restarted, or the network broke: resumed, a few times.
      if (++breaks > 5) throw;
      std::this_thread::sleep_for(std::chrono::seconds(breaks));
    }
  }
  return job;
}

int job_exit_code(const protocol::JobStatus& job) {
  if (job.state == JobState::completed) return kExitOk;
  if (job.error)
    std::fprintf(stderr, "job %s %s: %s\n", printable(job.id).c_str(), to_string(job.state),
                 printable(*job.error).c_str());
  else
    std::fprintf(stderr, "job %s %s\n", printable(job.id).c_str(), to_string(job.state));
  if (job.frames.total > 1 && job.frames.failed > 0)
    std::fprintf(stderr, "failed frames: %s (%d of %d)\n",
                 printable(job.frames.failed_list).c_str(), job.frames.failed, job.frames.total);
  return kExitJobFailed;
}

}  // namespace tessera
