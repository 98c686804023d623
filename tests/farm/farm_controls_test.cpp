// The farm's controls on real processes, through the CLI people use: short job ids,
// tables with human times, priority, pause and resume, retrying a failed job, draining and
// removing workers.
#include <cstdlib>
#include <regex>
#include <string>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using test::contains;
using test::Farm;

test::CliRun cli(Farm& farm, std::vector<std::string> args) {
  args.insert(args.begin(), {"--server", farm.url()});
  return test::run_cli(farm.dir(), args);
}

TEST(FarmControlsTest, AUniquePrefixOfAJobIdWorksEverywhereAndAnAmbiguousOneListsTheCandidates) {
  Farm farm("controls-ids", 0);
  std::vector<std::string> ids;
  for (int i = 0; i < 3; ++i)
    ids.push_back(
        farm.api().submit("job " + std::to_string(i), 50, test::showcase(16, 16, 1, 16))["id"]);
  const std::string& id = ids[1];
  // With "j-" or without it.
  for (const std::string& prefix : {id.substr(0, 10), id.substr(2, 8)}) {
    const test::CliRun status = cli(farm, {"status", prefix});
    EXPECT_EQ(status.exit_code, 0) << status.output;
    EXPECT_TRUE(contains(status.output, id)) << status.output;
  }
  const test::CliRun paused = cli(farm, {"pause", id.substr(0, 10)});
  EXPECT_EQ(paused.exit_code, 0) << paused.output;
  EXPECT_EQ(farm.api().job(id)["state"], "paused");
  // "j-" begins every id: the CLI names them all and changes nothing.
  const test::CliRun ambiguous = cli(farm, {"cancel", "j-"});
  EXPECT_EQ(ambiguous.exit_code, 1) << ambiguous.output;
  EXPECT_TRUE(contains(ambiguous.output, "ambiguous")) << ambiguous.output;
  for (const std::string& each : ids) {
    EXPECT_TRUE(contains(ambiguous.output, each)) << ambiguous.output;
    EXPECT_NE(farm.api().job(each)["state"], "canceled");
  }
  const test::CliRun none = cli(farm, {"status", "j-ffffffffffffffffffff"});
  EXPECT_EQ(none.exit_code, 1) << none.output;
  EXPECT_TRUE(contains(none.output, "no job j-ffffffffffffffffffff")) << none.output;
}

TEST(FarmControlsTest, AJobIsNamedByItsNameWhereNoOtherHasIt) {
  Farm farm("controls-names", 0);
  const std::string shot =
      farm.api().submit("nightly shot 12", 50, test::showcase(16, 16, 1, 16))["id"];
  const std::string first = farm.api().submit("dup", 50, test::showcase(16, 16, 1, 16))["id"];
  const std::string second = farm.api().submit("dup", 50, test::showcase(16, 16, 1, 16))["id"];
  const test::CliRun status = cli(farm, {"status", "nightly shot 12"});
  EXPECT_EQ(status.exit_code, 0) << status.output;
  EXPECT_TRUE(contains(status.output, shot)) << status.output;
  EXPECT_EQ(cli(farm, {"pause", "nightly shot 12"}).exit_code, 0);
  EXPECT_EQ(farm.api().job(shot)["state"], "paused");
  // Two jobs of one name: both are named, and nothing is done.
  const test::CliRun both = cli(farm, {"cancel", "dup"});
  EXPECT_EQ(both.exit_code, 1) << both.output;
  EXPECT_TRUE(contains(both.output, "more than one job is named dup")) << both.output;
  EXPECT_TRUE(contains(both.output, first) && contains(both.output, second)) << both.output;
  EXPECT_NE(farm.api().job(first)["state"], "canceled");
  // Neither an id nor a name: says so.
  const test::CliRun none = cli(farm, {"status", "no such name"});
  EXPECT_EQ(none.exit_code, 1) << none.output;
  EXPECT_TRUE(contains(none.output, "no job no such name, by id or by name")) << none.output;
}

TEST(FarmControlsTest, APausedJobWhoseTilesAreStillOutIsPausing) {
  Farm farm("controls-pausing", 0, {"--lease-timeout", "30", "--heartbeat-interval", "0.2"});
  // Eight tiles of a second or more each: the first is still out well after the pause, and
  // the others are left for after it.
  const std::string id =
      farm.api().submit("slow tiles", 50, test::showcase(512, 64, 768, 64))["id"];
  auto worker = farm.start_worker("steady", 1);
  ASSERT_TRUE(test::eventually(
      [&] {
        const json job = farm.api().job(id);
        return job["tiles"]["rendering"] >= 1 && job["tiles"]["done"] == 0;
      },
      30s));
  ASSERT_EQ(cli(farm, {"pause", id}).exit_code, 0);
  const test::CliRun status = cli(farm, {"status", id});
  const test::CliRun list = cli(farm, {"list"});
  const json job = farm.api().job(id);
  ASSERT_GE(job["tiles"]["rendering"], 1) << "the tiles were done before they could be seen out";
  EXPECT_TRUE(contains(status.output, " pausing ")) << status.output;
  EXPECT_TRUE(contains(list.output, " pausing ")) << list.output;
  // Once its tiles are in, it is paused, with tiles left to render.
  ASSERT_TRUE(test::eventually([&] { return farm.api().job(id)["tiles"]["rendering"] == 0; }, 60s));
  const json after = farm.api().job(id);
  ASSERT_LT(after["tiles"]["done"], 8) << after.dump();
  const test::CliRun paused = cli(farm, {"status", id});
  EXPECT_TRUE(contains(paused.output, " paused ")) << paused.output;
}

TEST(FarmControlsTest, ListAndWorkersPrintAHeaderAndHumanTimes) {
  Farm farm("controls-tables", 1);
  const json job = farm.api().submit("table <b>", 50, test::showcase(16, 16, 1, 16));
  ASSERT_EQ(farm.wait_finished(job["id"])["state"], "completed");
  const test::CliRun list = cli(farm, {"list"});
  ASSERT_EQ(list.exit_code, 0) << list.output;
  EXPECT_TRUE(std::regex_search(list.output, std::regex("^ID +NAME +STATE +DONE +TILES +PRIO +SIZE "
                                                        "+SUBMITTED\n")))
      << list.output;
  EXPECT_TRUE(std::regex_search(
      list.output,
      std::regex(job["id"].get<std::string>().substr(0, 10) +
                 " +table <b> +completed +100% +1/1 +50 +16x16 +(just now|[0-9]+ s ago)\n")))
      << list.output;
  // A long name is cut to its column, in whole characters; more jobs than shown are said.
  farm.api().submit("a name far too long for its column", 50, test::showcase(16, 16, 1, 16));
  farm.api().submit("été 日本 long enough to be cut", 50, test::showcase(16, 16, 1, 16));
  const test::CliRun cut = cli(farm, {"list", "--limit", "2"});
  ASSERT_EQ(cut.exit_code, 0) << cut.output;
  EXPECT_TRUE(std::regex_search(cut.output, std::regex(" a name far too long\u2026 +[a-z]")))
      << cut.output;
  EXPECT_TRUE(std::regex_search(cut.output, std::regex(" été 日本 long enough \u2026 +[a-z]")))
      << cut.output;
  EXPECT_NE(cut.output.find("(more jobs than these 2: tessera list --limit 4 shows more)"),
            std::string::npos)
      << cut.output;
  EXPECT_EQ(cli(farm, {"list"}).output.find("more jobs"), std::string::npos);
  const test::CliRun workers = cli(farm, {"workers"});
  ASSERT_EQ(workers.exit_code, 0) << workers.output;
  EXPECT_TRUE(std::regex_search(
      workers.output, std::regex("^ID +NAME +HOST +STATE +THREADS +TILES +JOB +LAST SEEN\n")))
      << workers.output;
  EXPECT_TRUE(
      std::regex_search(workers.output, std::regex("w-[0-9a-f]{12} .* (just now|[0-9]+ s ago)\n")))
      << workers.output;
}

TEST(FarmControlsTest, PriorityPauseAndResumeSteerARealWorker) {
  Farm farm("controls-pause", 0);
  // Many small tiles: the worker is still at it when it is paused.
  const std::string slow = farm.api().submit("slow", 50, test::showcase(256, 256, 4, 8))["id"];
  auto worker = farm.start_worker("steady", 1);
  ASSERT_TRUE(test::eventually([&] { return farm.api().job(slow)["tiles"]["done"] > 0; }, 60s));
  ASSERT_EQ(cli(farm, {"pause", slow}).exit_code, 0);
  // Its leases run out (delivered), and then nothing more of it is rendered, while another
  // job submitted afterwards is rendered whole by the same worker.
  ASSERT_TRUE(
      test::eventually([&] { return farm.api().job(slow)["tiles"]["rendering"] == 0; }, 60s));
  const int done = farm.api().job(slow)["tiles"]["done"];
  const std::string other = farm.api().submit("other", 10, test::showcase(32, 32, 1, 16))["id"];
  ASSERT_EQ(farm.wait_finished(other)["state"], "completed");
  EXPECT_EQ(farm.api().job(slow)["tiles"]["done"], done);
  EXPECT_EQ(farm.api().job(slow)["state"], "paused");
  // A new priority is shown at once; resumed, the job completes.
  const test::CliRun priority = cli(farm, {"priority", slow.substr(0, 12), "90"});
  EXPECT_EQ(priority.exit_code, 0) << priority.output;
  EXPECT_TRUE(contains(priority.output, "priority 90")) << priority.output;
  ASSERT_EQ(cli(farm, {"resume", slow}).exit_code, 0);
  const json finished = farm.wait_finished(slow, 180s);
  EXPECT_EQ(finished["state"], "completed");
  EXPECT_EQ(finished["priority"], 90);
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, slow),
                                test::render_image(test::showcase(256, 256, 4, 8), 2)));
}

TEST(FarmControlsTest, AFailedJobIsRetriedOnAHealthyWorkerAndItsImageIsWhole) {
  Farm farm("controls-retry", 0, {"--max-tile-attempts", "1"});
  const json scene = test::showcase(64, 32, 1, 16);  // 8 tiles; tile 0 is never the first out
  const std::string id = farm.api().submit("retried", 50, scene)["id"];
  {
    ::setenv("TESSERA_FAULT_INJECTION", "error:0", 1);
    auto faulty = farm.start_worker("faulty", 1);
    ::unsetenv("TESSERA_FAULT_INJECTION");
    ASSERT_EQ(farm.wait_finished(id)["state"], "failed");
    // Stopped as people stop a worker: it leaves, and its parked claim with it.
    faulty->signal(SIGTERM);
    ASSERT_TRUE(faulty->wait_for(30s));
  }
  const json failed = farm.api().job(id);
  EXPECT_LT(failed["tiles"]["done"], 8);
  // Refused while it is not failed, then retried: the tiles done are kept.
  auto healthy = farm.start_worker("healthy", 1);
  const test::CliRun retried = cli(farm, {"retry", id.substr(0, 10)});
  ASSERT_EQ(retried.exit_code, 0) << retried.output;
  const json finished = farm.wait_finished(id);
  ASSERT_EQ(finished["state"], "completed") << finished.dump();
  EXPECT_TRUE(finished["error"].is_null());
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, id), test::render_image(scene, 2)));
  const test::CliRun again = cli(farm, {"retry", id});
  EXPECT_EQ(again.exit_code, 1) << again.output;
  EXPECT_TRUE(contains(again.output, "only a failed or canceled job is retried")) << again.output;
}

TEST(FarmControlsTest, ADrainedWorkerTakesNoTilesAndARemovedOneIsForgotten) {
  Farm farm("controls-drain", 0);
  auto worker = farm.start_worker("drained", 1);
  ASSERT_TRUE(test::eventually([&] { return farm.worker_named("drained").has_value(); }, 20s));
  // By its name.
  const test::CliRun drained = cli(farm, {"drain", "drained"});
  ASSERT_EQ(drained.exit_code, 0) << drained.output;
  EXPECT_TRUE(contains(drained.output, "* draining")) << drained.output;
  EXPECT_EQ((*farm.worker_named("drained"))["draining"], true);
  const std::string id = farm.api().submit("waits", 50, test::showcase(16, 16, 1, 16))["id"];
  // The drained worker asks for work (its claims return empty) and gets none: after two
  // of its claims have come and gone, the job is still queued.
  const std::string seen = (*farm.worker_named("drained"))["last_seen"];
  ASSERT_TRUE(
      test::eventually([&] { return (*farm.worker_named("drained"))["last_seen"] != seen; }, 60s));
  EXPECT_EQ(farm.api().job(id)["state"], "queued");
  const std::string worker_id = (*farm.worker_named("drained"))["id"];
  ASSERT_EQ(cli(farm, {"undrain", worker_id.substr(0, 6)}).exit_code, 0);
  EXPECT_EQ(farm.wait_finished(id)["state"], "completed");
  // Removed, it leaves the list; the live process registers again, as a new worker.
  const test::CliRun removed = cli(farm, {"remove-worker", worker_id});
  ASSERT_EQ(removed.exit_code, 0) << removed.output;
  ASSERT_TRUE(test::eventually(
      [&] {
        const auto now = farm.worker_named("drained");
        return now && (*now)["id"] != worker_id;
      },
      60s));
  for (const json& listed : farm.api().workers()["workers"]) EXPECT_NE(listed["id"], worker_id);
}

}  // namespace
}  // namespace tessera
