// The event hub: each stream sees its own events, in order, resumes after the last one it
// saw while that is kept, and a subscriber that falls behind is sent "resync" instead of
// holding anything up.
#include "server/api/event_hub.hpp"

#include <gtest/gtest.h>

namespace tessera {
namespace {

// The events taken, as "type data" lines.
std::vector<std::string> taken(Subscription& subscription, bool* ended = nullptr) {
  bool end = false;
  const std::string text = subscription.take(end);
  if (ended) *ended = end;
  std::vector<std::string> events;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t stop = text.find("\n\n", at);
    std::string type, data;
    const std::string block = text.substr(at, stop - at);
    at = stop + 2;
    if (block.starts_with(":")) continue;  // the greeting, or a keep-alive
    std::istringstream lines(block);
    for (std::string line; std::getline(lines, line);) {
      if (line.starts_with("event: ")) type = line.substr(7);
      if (line.starts_with("data: ")) data = line.substr(6);
    }
    events.push_back(type + " " + data);
  }
  return events;
}

// The id of the last event of a take.
std::string last_id(const std::string& text) {
  const std::size_t at = text.rfind("id: ");
  return text.substr(at + 4, text.find('\n', at) - at - 4);
}

TEST(EventHubTest, EachStreamSeesItsOwnEventsInOrder) {
  EventHub hub;
  const auto all = hub.subscribe("", std::nullopt);
  const auto job_a = hub.subscribe("j-a", std::nullopt);
  const auto job_b = hub.subscribe("j-b", std::nullopt);
  hub.publish("job", "1", true, "j-a");
  hub.publish("tile", "2", false, "j-a");
  hub.publish("worker", "3", true);
  hub.publish("tile", "4", false, "j-b");
  EXPECT_EQ(taken(*all), (std::vector<std::string>{"job 1", "worker 3"}));
  EXPECT_EQ(taken(*job_a), (std::vector<std::string>{"job 1", "tile 2"}));
  EXPECT_EQ(taken(*job_b), (std::vector<std::string>{"tile 4"}));
  EXPECT_TRUE(taken(*all).empty()) << "taken once";
  EXPECT_EQ(hub.subscribers(), 3u);
}

TEST(EventHubTest, AWaitingStreamIsWokenByItsNextEvent) {
  EventHub hub;
  const auto job = hub.subscribe("j-a", std::nullopt);
  int woken = 0;
  job->wait([&] { ++woken; });
  EXPECT_EQ(woken, 1) << "the stream's opening comment is there at once";
  EXPECT_TRUE(taken(*job).empty());
  woken = 0;
  job->wait([&] { ++woken; });
  hub.publish("worker", "x", true);
  EXPECT_EQ(woken, 0) << "not its event";
  hub.publish("tile", "y", false, "j-a");
  EXPECT_EQ(woken, 1);
  hub.publish("tile", "z", false, "j-a");
  EXPECT_EQ(woken, 1) << "once per wait";
  job->wait([&] { ++woken; });
  EXPECT_EQ(woken, 2) << "something is there already";
}

TEST(EventHubTest, ALastEventIdResumesRightAfterIt) {
  EventHub hub;
  const auto first = hub.subscribe("j-a", std::nullopt);
  hub.publish("tile", "1", false, "j-a");
  hub.publish("tile", "2", false, "j-a");
  bool ended = false;
  const std::string text = first->take(ended);
  const std::string seen = last_id(text);
  first->cancel();
  hub.publish("tile", "3", false, "j-a");
  hub.publish("worker", "w", true);
  hub.publish("tile", "4", false, "j-a");
  const auto resumed = hub.subscribe("j-a", seen);
  EXPECT_EQ(taken(*resumed), (std::vector<std::string>{"tile 3", "tile 4"}));
}

TEST(EventHubTest, AnIdNoLongerKeptOrFromAnotherProcessResyncs) {
  EventLimits limits;
  limits.kept_events = 2;
  EventHub hub(limits);
  const auto probe = hub.subscribe("", std::nullopt);
  hub.publish("job", "1", true);
  bool ended = false;
  const std::string old_id = last_id(probe->take(ended));
  for (int i = 0; i < 5; ++i) hub.publish("job", std::to_string(i + 2), true);
  const auto late = hub.subscribe("", old_id);
  const auto lines = taken(*late);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(lines[0].starts_with("resync ")) << lines[0];
  // An id of another coordinator process (restarted), or none it could have given.
  for (const std::string& bogus :
       std::vector<std::string>{"0123abcd-1", "garbage", old_id + "0000"}) {
    const auto other = hub.subscribe("", bogus);
    const auto seen = taken(*other);
    ASSERT_EQ(seen.size(), 1u) << bogus;
    EXPECT_TRUE(seen[0].starts_with("resync ")) << bogus;
  }
}

TEST(EventHubTest, ASubscriberThatFallsBehindIsSentResyncAndThenFollows) {
  EventLimits limits;
  limits.queue_events = 3;
  EventHub hub(limits);
  const auto slow = hub.subscribe("", std::nullopt);
  const auto fast = hub.subscribe("", std::nullopt);
  for (int i = 0; i < 5; ++i) {
    hub.publish("job", std::to_string(i), true);
    taken(*fast);  // keeps up
  }
  const auto lines = taken(*slow);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(lines[0].starts_with("resync {\"reason\":")) << lines[0];
  hub.publish("job", "5", true);
  EXPECT_EQ(taken(*slow), (std::vector<std::string>{"job 5"}));
}

TEST(EventHubTest, EndingAllEndsEachStreamOnceTaken) {
  EventHub hub;
  const auto stream = hub.subscribe("", std::nullopt);
  hub.publish("job", "1", true);
  int woken = 0;
  hub.end_all();
  bool ended = false;
  EXPECT_EQ(taken(*stream, &ended), (std::vector<std::string>{"job 1"}));
  EXPECT_FALSE(ended) << "what was queued goes first";
  stream->wait([&] { ++woken; });
  EXPECT_EQ(woken, 1);
  EXPECT_TRUE(taken(*stream, &ended).empty());
  EXPECT_TRUE(ended);
}

TEST(EventHubTest, AStreamResumedAcrossATimeNobodyFollowedItsJobResyncs) {
  EventHub hub;
  auto first = hub.subscribe("j-a", std::nullopt);
  EXPECT_TRUE(hub.follows_or_skips("j-a"));
  hub.publish("tile", "1", false, "j-a");
  bool ended = false;
  const std::string seen = last_id(first->take(ended));
  first.reset();  // the client went
  // Nobody follows the job: its tile events are not made meanwhile.
  EXPECT_FALSE(hub.follows_or_skips("j-a"));
  const auto resumed = hub.subscribe("j-a", seen);
  const auto lines = taken(*resumed);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(lines[0].starts_with("resync ")) << lines[0];
  // Followed again, its events are made, and a stream resumes after them as usual.
  EXPECT_TRUE(hub.follows_or_skips("j-a"));
  hub.publish("tile", "2", false, "j-a");
  const std::string two = last_id(resumed->take(ended));
  hub.publish("tile", "3", false, "j-a");
  EXPECT_EQ(taken(*hub.subscribe("j-a", two)), (std::vector<std::string>{"tile 3"}));
}

}  // namespace
}  // namespace tessera
